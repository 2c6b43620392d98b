import sys, collections, statistics, glob, os
import numpy as np
d = collections.defaultdict(list)
for l in open(sys.argv[1]):
    f = l.split()
    if len(f) > 4 and f[4] == 'Msamples/s' and f[0] != '0':
        d[(f[1], f[2])].append(float(f[3]))
cfgs = []
for (c, s) in d:
    if c not in cfgs: cfgs.append(c)
def pfm(path):
    with open(path, 'rb') as fh:
        kind = fh.readline().strip(); w, h = map(int, fh.readline().split()); scale = float(fh.readline())
        a = np.frombuffer(fh.read(), dtype='<f4' if scale < 0 else '>f4')
    return a.reshape(h, w, -1)
print('| cfg | cornell | gold | glass | means |')
for c in cfgs:
    row = []
    for s in ('cornell', 'gold', 'glass'):
        v = d.get((c, s), [])
        b = d.get(('base', s), [])
        row.append('%s (%.3f)' % ('/'.join('%.0f' % x for x in v), (statistics.median(v) / statistics.median(b)) if v and b else 0))
    means = []
    for s in ('cornell', 'gold', 'glass'):
        p = os.path.join(sys.argv[2], 'o_%s_%s.pfm' % (c, s))
        means.append('%.5f' % pfm(p).mean() if os.path.exists(p) else '-')
    print('| %s | %s | %s |' % (c, ' | '.join(row), ' '.join(means)))
