# Splits each triangle of an OBJ into 4^levels coplanar ones (midpoints shared by edge): the probe
# of a finer glass sphere. Usage: subdivide.py IN.obj OUT.obj LEVELS
import sys
src, dst, levels = sys.argv[1], sys.argv[2], int(sys.argv[3])
V=[]; F=[]; other=[]
for l in open(src):
    p=l.split()
    if not p: continue
    if p[0]=='v': V.append(tuple(map(float,p[1:4])))
    elif p[0]=='f': F.append(tuple(int(x.split('/')[0]) - 1 for x in p[1:]))
    else: other.append(l)
for _ in range(levels):
    mid={}
    def m(a,b):
        k=(min(a,b),max(a,b))
        if k not in mid:
            V.append(tuple((x+y)/2 for x,y in zip(V[a],V[b]))); mid[k]=len(V)-1
        return mid[k]
    NF=[]
    for a,b,c in F:
        ab,bc,ca=m(a,b),m(b,c),m(c,a)
        NF += [(a,ab,ca),(ab,b,bc),(ca,bc,c),(ab,bc,ca)]
    F=NF
with open(dst,'w') as o:
    for l in other: o.write(l)
    for v in V: o.write('v %.9g %.9g %.9g\n'%v)
    for f in F: o.write('f %d %d %d\n'%tuple(i+1 for i in f))
print(dst, len(V), len(F))
