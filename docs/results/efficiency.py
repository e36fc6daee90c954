#!/usr/bin/env python3
"""Efficiency table from a kalos experiment's results.csv.

Usage: python3 docs/results/efficiency.py RESULTS.csv BASELINE_CONFIG
Per (config, budget): mean MSE, mean seconds and rays-free efficiency 1 / (MSE x seconds)
over the seeds, and its ratio to the baseline's at the same budget."""
import csv, sys
from collections import defaultdict

rows = list(csv.DictReader(open(sys.argv[1])))
base = sys.argv[2]
acc = defaultdict(lambda: [0.0, 0.0, 0.0, 0])
order = []
for r in rows:
    k = (r["config"], float(r["budget"]))
    if k[0] not in order:
        order.append(k[0])
    a = acc[k]
    a[0] += float(r["mse"]); a[1] += float(r["seconds"]); a[2] += float(r["perceptual_share"]); a[3] += 1
budgets = sorted({k[1] for k in acc})
print(f"{'config':<20} {'budget':>7} {'mse':>11} {'seconds':>8} {'efficiency':>11} {'vs ' + base:>12} {'mse ratio':>9}")
for c in order:
    for b in budgets:
        if (c, b) not in acc:
            continue
        m, s, p, n = acc[(c, b)]
        m, s = m / n, s / n
        e = 1.0 / (m * s)
        bm, bs, _, bn = acc[(base, b)]
        be = 1.0 / ((bm / bn) * (bs / bn))
        print(f"{c:<20} {b:>7g} {m:>11.4e} {s:>8.3f} {e:>11.4g} {e / be:>12.2f} {(bm / bn) / m:>9.2f}")
