# k-W's warp model: the PFM holds, at each modelled warp's first pixel, (extension turns'
# lane iterations, 32 x their largest, the warp's extension turns) and at its second
# (shadow turns' lane iterations, 32 x their largest, lane turns whose samples were done),
# and at its third (both kinds' sums of 32 x the largest over the lanes still at work),
# each / (spp x 2^20). Work-groups of 8 x 8: a modelled warp is 8 x 4 pixels.
import json, struct, sys
pfm, js, label = sys.argv[1], sys.argv[2], sys.argv[3]
j = json.load(open(js)); data = open(pfm, 'rb').read(); parts = data.split(b'\n', 3)
w, h = map(int, parts[1].split()); v = struct.unpack('<%df' % (w * h * 3), parts[3][:w * h * 12])
scale = 1048576.0 * j['spp']
px = [(v[3 * i], v[3 * i + 1], v[3 * i + 2]) for i in range(w * h)]
# PFM rows run bottom to top; the warp's first and second pixels are neighbours in a row.
first = [p for i, p in enumerate(px) if (i % w) % 8 == 0]; second = [p for i, p in enumerate(px) if (i % w) % 8 == 1]
third = [p for i, p in enumerate(px) if (i % w) % 8 == 2]
fourth = [p for i, p in enumerate(px) if (i % w) % 8 == 3]
s = lambda rows, k: sum(r[k] for r in rows) * scale
ea, em, et = s(first, 0), s(first, 1), s(first, 2)
sa, sm, idle = s(second, 0), s(second, 1), s(second, 2)
ea2, sa2 = s(third, 0), s(third, 1)
print('%s: extension turns %.3f, shadow turns %.3f, both %.3f (lane iterations / 32 x warp largest); '
      'over the lanes at work: %.3f, %.3f, %.3f; '
      'iterations a lane: extension %.2f, shadow %.2f a turn; lanes idle with their samples done %.1f%%'
      % (label, ea / em, sa / max(sm, 1), (ea + sa) / (em + sm), ea / ea2, sa / max(sa2, 1), (ea + sa) / (ea2 + sa2),
         ea / (32 * et), sa / (32 * et), 100 * idle / (2 * 32 * et)))
print('%s: warp iterations a sample (the traversal time a SIMD group spends, per pixel sample) %.2f; warp turns a sample %.3f'
      % (label, (em + sm) / 32 / (w * h * j['spp']) * 32, et * 2 / (w * h * j['spp']) * 32))
pm = s(fourth, 0)
if pm > 0:
    print('%s: each shadow ray traced with the next extension ray in one turn: the group\'s iterations a sample %.2f (x%.3f)'
          % (label, pm / (w * h * j['spp']), (em + sm) / pm))
