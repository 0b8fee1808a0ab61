#!/usr/bin/env python3
"""How much of a vdmap global map is repeated between merge groups (docs/results.md).

Usage: scripts/voxel_overlap.py OUT/global_ellipsoids.ply [VOXEL_M ...]   (default 0.02 0.01)

Counts the distinct voxels the ellipsoid means fall into, and how many ellipsoids share their
voxel with an ellipsoid of another keyframe label: a merged ellipsoid carries its merge group's
centre keyframe, one that passed through unmerged its own keyframe, so ellipsoids of two labels
in one voxel are copies of a surface that merging never compared. Plain Python, no NumPy.
"""
import collections
import struct
import sys

path = sys.argv[1]
sizes = [float(s) for s in sys.argv[2:]] or [0.02, 0.01]
data = open(path, 'rb').read()
end = data.find(b'end_header\n') + len(b'end_header\n')
header = data[:end].decode('ascii', 'replace')
if end < len(b'end_header\n') or 'property int keyframe' not in header or 'format binary_little_endian' not in header:
    sys.exit(f'{path}: not a vdmap ellipsoid PLY (docs/method.md 11)')
n = int(header.split('element vertex ')[1].split()[0])
record = struct.Struct('<3f3B6fIi')  # x y z, rgb, 6 covariance entries, count, keyframe
means = [(x, y, z, keyframe) for x, y, z, *_, keyframe in record.iter_unpack(data[end:end + n * record.size])]
for size in sizes:
    groups = collections.defaultdict(set)
    count = collections.Counter()
    for x, y, z, keyframe in means:
        key = (int(x // size), int(y // size), int(z // size))
        groups[key].add(keyframe)
        count[key] += 1
    shared = sum(count[k] for k, g in groups.items() if len(g) > 1)
    print(f'{size * 100:g} cm voxels: {n} ellipsoids in {len(groups)} voxels ({n / len(groups):.2f} each); '
          f'{shared} ({100 * shared / n:.1f} %) share their voxel with another keyframe label')
