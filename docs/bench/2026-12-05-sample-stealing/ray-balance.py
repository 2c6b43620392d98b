#!/usr/bin/env python3
"""How evenly the work-items of a SIMD group share a launch's path tracing: from a dump of
the rays each pixel traced (one row of counts per image row, CLTRACE_DUMP_RAYS on the
branch exp/steal), the rays of each 16 x 2 group of pixels (a 32-wide SIMD group of a 16 x 8
work-group) over 32 times their largest count."""
import sys
import numpy as np

for path in sys.argv[1:]:
    a = np.loadtxt(path)
    h, w = a.shape
    b = a[: h // 2 * 2, : w // 16 * 16].reshape(h // 2, 2, w // 16, 16).transpose(0, 2, 1, 3).reshape(-1, 32)
    print(f"{path}: {b.sum() / (b.max(axis=1).sum() * 32):.3f}")
