"""Items 1 and 2 by camera framing (docs/bench/2026-12-06-framings.md): compare.py's gold and
glass scenes under four camera framings, Mitsuba and cltrace on each of DEVICES alternated
within every round, Msamples/s per round. Run from the repository root.

On 2 cores (the defaults): Mitsuba llvm_ad_rgb, cltrace on Intel's runtime (0:0) and PoCL
(1:0), 512x512, 64 spp. On the GPU: VARIANT=cuda_ad_rgb DEVICES=gpu W=1920 H=1080 SPP=256.
EXTRA adds cltrace render options (run24.sh: --layout)."""
import sys, os, json, time, subprocess
sys.path.insert(0, os.path.join(os.getcwd(), "scripts/mitsuba"))
import compare as C
import numpy as np
mi = C.mitsuba(os.environ.get("VARIANT", "llvm_ad_rgb"))
import drjit as dr
W, H = int(os.environ.get("W", 512)), int(os.environ.get("H", 512))
SPP = int(os.environ.get("SPP", 64)); ROUNDS = int(os.environ.get("ROUNDS", 4))
DEVICES = os.environ.get("DEVICES", "0:0,1:0").split(",")
EXTRA = os.environ.get("EXTRA", "").split()
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
                    "-o", f"{out}/s.exr", "--json", f"{out}/r.json"] + EXTRA, check=True)
    r = json.load(open(f"{out}/r.json"))
    return W * H * SPP / r["sampling_ms"] * 1e3 / 1e6, r["rays"] / (W * H * SPP)
for name, view, out, loaded in cases:  # warm-up: Mitsuba's JIT, cltrace's programs
    mitsuba(loaded, 0)
    for dev in DEVICES: cltrace(out, dev)
res = {(n, v): {"mitsuba": [], **{dev: [] for dev in DEVICES}} for n, v, _, _ in cases}
rays = {}
for r in range(ROUNDS):
    for name, view, out, loaded in cases:
        d = res[(name, view)]
        d["mitsuba"].append(mitsuba(loaded, r + 1))
        for dev in DEVICES:
            x, rays[(name, view)] = cltrace(out, dev); d[dev].append(x)
        print(f"round {r} {name} {view}: " + " ".join(f"{k} {v[-1]:.2f}" for k, v in d.items()), flush=True)
print("| scene | view | rays a sample | Mitsuba | " + " | ".join(f"cltrace {d}" for d in DEVICES) + " | "
      + " | ".join(f"{d}/Mitsuba per round" for d in DEVICES) + " |")
print("|---|---|---:|---:|" + "---:|" * len(DEVICES) + "---|" * len(DEVICES))
for (n, v), d in res.items():
    m = np.array(d["mitsuba"])
    cols = [np.array(d[dev]) for dev in DEVICES]
    print(f"| {n} | {v} | {rays[(n, v)]:.2f} | {np.median(m):.2f} | " + " | ".join(f"{np.median(c):.2f}" for c in cols)
          + " | " + " | ".join(", ".join(f"{x:.2f}" for x in c / m) for c in cols) + " |")
