"""Sums, over the SIMD groups of 32 rays a pixel tiling makes, the most nodes and triangles
any ray of the group visits: a SIMD machine's steps if its rays diverge freely. Usage:
python3 simt.py W H FILE.hits... (from count-steps.py)."""
import numpy as np, sys
W, H = int(sys.argv[1]), int(sys.argv[2])
for m in sys.argv[3:]:
    a = np.fromfile(m, dtype=np.uint32).reshape(H, W, 2)
    tests = a[:, :, 0].astype(np.int64)
    visits = a[:, :, 1].view(np.float32).astype(np.int64)
    print(m, "rays", W*H, "mean visits", visits.mean().round(3), "mean tests", tests.mean().round(3), "max visits", visits.max())
    for tw, th in [(32, 1), (16, 2), (8, 4), (4, 8)]:
        v = visits.reshape(H // th, th, W // tw, tw).transpose(0, 2, 1, 3).reshape(-1, tw * th)
        t = tests.reshape(H // th, th, W // tw, tw).transpose(0, 2, 1, 3).reshape(-1, tw * th)
        busy = (v.max(1) > 1)
        print(f"  {tw}x{th}: sum max visits {v.max(1).sum():>10}  sum max tests {t.max(1).sum():>9}  warps>1 visit {busy.sum():>6}  lane util {v.sum()/ (v.max(1).sum()*32):.3f}")
