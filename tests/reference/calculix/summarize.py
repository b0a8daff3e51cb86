#!/usr/bin/python3
"""Prints Markdown tables from ball_reference.csv: fine-mesh values, the change
coarse -> fine, and the comparison with Hertz / Lamb (used for README.md)."""
import csv
import os
import sys

path = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                            'ball_reference.csv')
rows = list(csv.DictReader(open(path)))
val = {}
for r in rows:
    val[(r['material'], r['case'], r['quantity'], r['travel_mm'], r['theory'], r['mesh'])] = float(r['value'])

keys = []
for r in rows:
    k = (r['material'], r['case'], r['quantity'], r['travel_mm'], r['unit'])
    if r['mesh'] in ('coarse', 'fine') and k not in keys:
        keys.append(k)

ANALYTIC = {'tip_force': 'hertz', 'floor_reaction': 'exact', 'T2': 'lamb', 'S2': 'lamb', 'S0': 'lamb'}

print('| material | case | quantity | travel mm | theory | fine | coarse | fine/coarse-1 | analytic | fine/analytic-1 |')
print('|---|---|---|---|---|---|---|---|---|---|')
for m, c, q, t, unit in keys:
    for th in ('small_strain', 'nlgeom'):
        f = val.get((m, c, q, t, th, 'fine'))
        co = val.get((m, c, q, t, th, 'coarse'))
        if f is None and co is None:
            continue
        a = val.get((m, c, q, t, ANALYTIC.get(q, '-'), 'analytic'))
        if q == 'tip_force' and c == 'tip_centre_held':
            a = val.get((m, c, q, t, 'hertz', 'analytic'))
        if q in ('tip_force_clamp25mm', 'tip_force_node_pin'):
            a = val.get((m, c, 'tip_force', t, 'hertz', 'analytic'))

        def fmt(v):
            return '' if v is None else '%.5g' % v

        def rel(x, y):
            return '' if x is None or y is None or y == 0 else '%+.2f %%' % (100 * (x / y - 1))

        print('| %s | %s | %s | %s | %s | %s %s | %s | %s | %s | %s |'
              % (m, c, q, t, th, fmt(f), unit, fmt(co), rel(f, co), fmt(a), rel(f if f is not None else co, a)))
