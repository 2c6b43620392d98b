"""Does a Mitsuba render just before slow down the cltrace render that follows it in
compare.py speed? cltrace's samples stage on gold, right after mi.render (as compare.py
runs it) and after a 3 s pause, alternated."""
import json, os, subprocess, sys, time
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "../../../scripts/mitsuba"))
import compare as c
import numpy as np
mi = c.mitsuba("llvm_ad_rgb")
import drjit as dr
name = sys.argv[1] if len(sys.argv) > 1 else "gold"
w, h, spp = 512, 512, 64
scene = c.SCENES[name](); scene["max_bounces"] = 8
out = f"/tmp/after-mitsuba/{name}"
c.write_inputs(scene, out, w, h, spp)
loaded = c.mitsuba_scene(mi, scene, out, w, h, spp, 8, c.RR_DEPTH_OF_CLTRACE)
def cl(dev):
    cmd = [os.environ.get("CLTRACE", "target/release/cltrace"), "render", os.path.join(out, "scene.toml"), "-q", "--device", dev,
           "--max-bounces", "8", "-o", os.path.join(out, "x.exr"), "--json", os.path.join(out, "r.json")]
    subprocess.run(cmd, check=True)
    return json.load(open(os.path.join(out, "r.json")))["sampling_ms"]
for k in range(5):
    t = time.perf_counter(); img = mi.render(loaded, spp=spp, seed=k); dr.eval(img); np.array(img)
    tm = time.perf_counter() - t
    after = cl(sys.argv[2] if len(sys.argv) > 2 else "1:0")
    time.sleep(3)
    paused = cl(sys.argv[2] if len(sys.argv) > 2 else "1:0")
    print(f"{name} round {k}: mitsuba {tm*1e3:.0f} ms; cltrace right after {after:.0f} ms, after 3 s pause {paused:.0f} ms", flush=True)
