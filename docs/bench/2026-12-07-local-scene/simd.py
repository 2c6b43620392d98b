# SIMD efficiency from k-M's render: the PFM holds per pixel (traversal iterations,
# 65536 x SIMD-group iterations, 65536 x SIMD-group turns) / (spp x 2^20); the JSON's rays are
# the lane turns.
import json, struct, sys
pfm, js, label = sys.argv[1], sys.argv[2], sys.argv[3]
j = json.load(open(js))
data = open(pfm, 'rb').read()
parts = data.split(b'\n', 3)
w, h = map(int, parts[1].split())
vals = struct.unpack('<%df' % (w * h * 3), parts[3][:w * h * 12])
spp = j['spp']; scale = 1048576.0 * spp
X = sum(vals[0::3]) * scale; Y = sum(vals[1::3]) * scale / 65536; Z = sum(vals[2::3]) * scale / 65536
lanes = j['rays']
print('%s: traversal iterations %.4g, per lane-turn %.2f; traversal SIMD efficiency %.3f; loop-turn efficiency %.3f; lane turns %d, group turns %.4g'
      % (label, X, X / lanes, X / (32 * Y), lanes / (32 * Z), lanes, Z))
