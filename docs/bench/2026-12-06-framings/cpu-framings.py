"""Item 1 by camera framing (docs/bench/2026-12-06-framings.md). Alternated rounds: Mitsuba llvm_ad_rgb, cltrace on Intel's runtime (0:0) and on PoCL (1:0),
on compare.py's gold and glass scenes under four camera framings, Msamples/s per round."""
import sys, os, json, time, subprocess
sys.path.insert(0, os.path.join(os.getcwd(), "scripts/mitsuba"))  # run from the repository root
import compare as C
import numpy as np
mi = C.mitsuba("llvm_ad_rgb")
import drjit as dr
W = H = int(os.environ.get("SIZE", 512)); SPP = int(os.environ.get("SPP", 64)); ROUNDS = int(os.environ.get("ROUNDS", 4))
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
        out = f"/tmp/framings/{name}-{view}"
        C.write_inputs(scene, out, W, H, SPP)
        loaded = C.mitsuba_scene(mi, scene, out, W, H, SPP, 8, C.RR_DEPTH_OF_CLTRACE)
        cases.append((name, view, out, loaded))
def mitsuba(loaded, k):
    s = time.perf_counter(); img = mi.render(loaded, spp=SPP, seed=k); dr.eval(img); np.array(img)
    return W * H * SPP / (time.perf_counter() - s) / 1e6
def cltrace(out, dev):
    subprocess.run([CL, "render", f"{out}/scene.toml", "-q", "--device", dev, "--max-bounces", "8",
                    "-o", f"{out}/s.exr", "--json", f"{out}/r.json"], check=True)
    r = json.load(open(f"{out}/r.json"))
    return W * H * SPP / r["sampling_ms"] * 1e3 / 1e6, r["rays"] / (W * H * SPP)
for name, view, out, loaded in cases:  # warm-up: Mitsuba's JIT, cltrace's programs
    mitsuba(loaded, 0); cltrace(out, "0:0"); cltrace(out, "1:0")
res = {(n, v): {"m": [], "i": [], "p": []} for n, v, _, _ in cases}
rays = {}
for r in range(ROUNDS):
    for name, view, out, loaded in cases:
        d = res[(name, view)]
        d["m"].append(mitsuba(loaded, r + 1))
        x, rays[(name, view)] = cltrace(out, "0:0"); d["i"].append(x)
        x, _ = cltrace(out, "1:0"); d["p"].append(x)
        print(f"round {r} {name} {view}: mitsuba {d['m'][-1]:.2f} intel {d['i'][-1]:.2f} pocl {d['p'][-1]:.2f}", flush=True)
print("| scene | view | rays a sample | Mitsuba | Intel | PoCL | Intel/Mitsuba per round | PoCL/Mitsuba per round |")
print("|---|---|---:|---:|---:|---:|---|---|")
for (n, v), d in res.items():
    m, i, p = (np.array(d[k]) for k in "mip")
    print(f"| {n} | {v} | {rays[(n, v)]:.2f} | {np.median(m):.2f} | {np.median(i):.2f} | {np.median(p):.2f} | "
          f"{', '.join(f'{x:.2f}' for x in i / m)} | {', '.join(f'{x:.2f}' for x in p / m)} |")
