"""Alternated rounds on the GPU: Mitsuba cuda_ad_rgb and cltrace (--device gpu) on compare.py's
gold and glass scenes under four camera framings, 1920x1080, 256 spp, Msamples/s per round."""
import sys, os, json, time, subprocess
sys.path.insert(0, os.path.join(os.getcwd(), "scripts/mitsuba"))
import compare as C
import numpy as np
mi = C.mitsuba(os.environ.get("VARIANT", "cuda_ad_rgb"))
import drjit as dr
W, H = int(os.environ.get("W", 1920)), int(os.environ.get("H", 1080)); SPP = int(os.environ.get("SPP", 256)); ROUNDS = int(os.environ.get("ROUNDS", 4))
DEV = os.environ.get("DEV", "gpu")
CL = os.environ.get("CL", os.path.join(os.getcwd(), "target/release/cltrace"))
views = {
    "open": None,
    "away": {"eye": (0.0, 1.3, 2.6), "look_at": (0.0, 1.3, 10.0), "up": (0, 1, 0), "fov": 40.0},
    "floor": {"eye": (0.0, 1.3, 2.6), "look_at": (1.2, 0.0, 1.2), "up": (0, 1, 0), "fov": 20.0},
    "sphere": {"eye": (0.0, 1.3, 2.6), "look_at": (0.0, 0.5, 0.0), "up": (0, 1, 0), "fov": 10.0},
}
names = sys.argv[1].split(",") if len(sys.argv) > 1 else ["gold", "glass"]
cases = []
for name in names:
    for view, cam in views.items():
        scene = C.SCENES[name]()
        scene["max_bounces"] = 8
        if cam: scene["camera"] = cam
        out = f"/tmp/frames/{name}-{view}"
        C.write_inputs(scene, out, W, H, SPP)
        loaded = C.mitsuba_scene(mi, scene, out, W, H, SPP, 8, C.RR_DEPTH_OF_CLTRACE)
        cases.append((name, view, out, loaded))
def mitsuba(loaded, k):
    s = time.perf_counter(); img = mi.render(loaded, spp=SPP, seed=k); dr.eval(img); np.array(img)
    return W * H * SPP / (time.perf_counter() - s) / 1e6
def cltrace(out, dev):
    subprocess.run([CL, "render", f"{out}/scene.toml", "-q", "--device", dev, "--max-bounces", "8",
                    "-o", f"{out}/s.exr", "--json", f"{out}/r.json"] + os.environ.get("EXTRA", "").split(), check=True)
    r = json.load(open(f"{out}/r.json"))
    return W * H * SPP / r["sampling_ms"] * 1e3 / 1e6, r["rays"] / (W * H * SPP)
for name, view, out, loaded in cases:  # warm-up: Mitsuba's JIT, cltrace's programs
    mitsuba(loaded, 0); cltrace(out, DEV)
res = {(n, v): {"m": [], "i": [], "p": []} for n, v, _, _ in cases}
rays = {}
for r in range(ROUNDS):
    for name, view, out, loaded in cases:
        d = res[(name, view)]
        d["m"].append(mitsuba(loaded, r + 1))
        x, rays[(name, view)] = cltrace(out, DEV); d["i"].append(x)
        d["p"].append(x)
        print(f"round {r} {name} {view}: mitsuba {d['m'][-1]:.1f} cltrace {d['i'][-1]:.1f}", flush=True)
print("| scene | view | rays a sample | Mitsuba | cltrace | ratio per round |")
print("|---|---|---:|---:|---:|---|")
for (n, v), d in res.items():
    m, i, p = (np.array(d[k]) for k in "mip")
    print(f"| {n} | {v} | {rays[(n, v)]:.2f} | {np.median(m):.1f} | {np.median(i):.1f} | "
          f"{', '.join(f'{x:.2f}' for x in i / m)} |")
