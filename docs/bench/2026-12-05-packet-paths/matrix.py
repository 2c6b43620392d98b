#!/usr/bin/env python3
"""Alternated rounds of cltrace render over configs x scenes; prints Msamples/s medians."""
import json, os, subprocess, sys, statistics
B = os.environ.get("BIN", "/tmp/cltrace-main")
SC = sys.argv[1]
rounds = int(sys.argv[2])
configs = [c.split() for c in sys.argv[3].split(";")]
scenes = sys.argv[4].split(",")
extra_env = {}
res = {}
def run(scene, cfg, env):
    js = "/tmp/m.json"
    b = next((a[2:] for a in cfg if a.startswith("B=")), B)
    cmd = [b, "render", f"{SC}/{scene}/scene.toml", "-q", "--device", os.environ.get("DEV", "gpu"), "--max-bounces", "8",
           "-o", "/tmp/m.exr", "--json", js] + [a for a in cfg if not a.startswith(("K=", "E=", "B="))]
    e = dict(os.environ)
    for a in cfg:
        if a.startswith("K="):
            e["CLTRACE_KERNEL_DIR"] = a[2:]
        if a.startswith("E="):
            k, v = a[2:].split("=", 1)
            e[k] = v
    r = subprocess.run(cmd, env=e, capture_output=True, text=True, timeout=120)
    if r.returncode != 0:
        return None, r.stderr.strip()[-300:]
    j = json.load(open(js))
    return j, ""
for scene in scenes:
    for cfg in configs:  # warm-up: compile
        j, err = run(scene, cfg, None)
        if j is None: print("FAIL", scene, cfg, err, flush=True)
for k in range(rounds):
    order = configs if k % 2 == 0 else configs[::-1]
    for scene in scenes:
        for cfg in order:
            j, err = run(scene, cfg, None)
            if j is None: continue
            samples = j["width"] * j["height"] * j["spp"]
            res.setdefault((scene, " ".join(cfg)), []).append(samples / (j["sampling_ms"] / 1e3) / 1e6)
            if k == 0 and cfg == configs[0]:
                print(scene, "device", j.get("device"), "rays", j.get("rays"), flush=True)
print("| scene | config | Msamples/s (each round) | median |")
for (scene, cfg), v in res.items():
    print(f"| {scene} | {cfg or 'default'} | {', '.join(f'{x:.1f}' for x in v)} | {statistics.median(v):.1f} |")
