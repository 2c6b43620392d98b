"""Writes the dragon turned upright for run36-37.sh (a quarter turn about z: x, y -> -y, x),
outside the project: python3 standing.py ../shared/scenes/stanford_dragon.obj.gz
.gpu/scenes/dragon_standing.obj.gz"""
import gzip, sys
out = gzip.open(sys.argv[2], "wt", compresslevel=6)
for line in gzip.open(sys.argv[1], "rt"):
    if line.startswith("v ") or line.startswith("vn "):
        t, x, y, z = line.split()[:4]
        out.write(f"{t} {-float(y)!r} {x} {z}\n")
    else:
        out.write(line)
out.close()
