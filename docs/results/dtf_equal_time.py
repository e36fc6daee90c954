#!/usr/bin/env python3
"""Equal-time ratios from a kalos experiment's results.csv (equal-spp budgets).

Usage: python3 docs/results/dtf_equal_time.py RESULTS.csv [BASELINE_CONFIG=path]

Per (config, budget), averaged over the seeds: RMSE, perceptual share and seconds. The
baseline's error *at the config's own time* is read off the baseline's measured
error-versus-time curve, interpolated linearly in log-log between its budgets (beyond the
ends: RMSE extrapolated with the Monte Carlo slope -1/2, the perceptual share with the
nearest segment's slope). The ratios printed are config / baseline at equal time."""
import csv, math, sys
from collections import defaultdict

rows = list(csv.DictReader(open(sys.argv[1])))
base = sys.argv[2] if len(sys.argv) > 2 else "path"
acc = defaultdict(lambda: [0.0, 0.0, 0.0, 0])
order = []
for r in rows:
    k = (r["config"], float(r["budget"]))
    if k[0] not in order:
        order.append(k[0])
    a = acc[k]
    a[0] += float(r["rmse"]); a[1] += float(r["perceptual_share"]); a[2] += float(r["seconds"]); a[3] += 1
mean = {k: (v[0] / v[3], v[1] / v[3], v[2] / v[3]) for k, v in acc.items()}
curve = sorted((t, e, p) for (c, _), (e, p, t) in mean.items() if c == base)


def at(t, idx, end_slope):
    """Baseline metric idx (1 rmse, 2 perceptual) at time t, log-log interpolation."""
    pts = [(math.log(c[0]), math.log(c[idx])) for c in curve]
    lt = math.log(t)
    if lt <= pts[0][0]:
        (x0, y0), (x1, y1) = pts[0], pts[1]
        slope = end_slope if end_slope is not None else (y1 - y0) / (x1 - x0)
        return math.exp(y0 + slope * (lt - x0))
    if lt >= pts[-1][0]:
        (x0, y0), (x1, y1) = pts[-2], pts[-1]
        slope = end_slope if end_slope is not None else (y1 - y0) / (x1 - x0)
        return math.exp(y1 + slope * (lt - x1))
    for (x0, y0), (x1, y1) in zip(pts, pts[1:]):
        if x0 <= lt <= x1:
            return math.exp(y0 + (y1 - y0) * (lt - x0) / (x1 - x0))


print(f"{'config':<18} {'budget':>6} {'seconds':>8} {'rmse':>9} {'perc':>7} "
      f"{'rmse vs ' + base + ' @ equal time':>28} {'perc vs ' + base + ' @ equal time':>28}")
for c in order:
    for b in sorted({k[1] for k in mean if k[0] == c}):
        e, p, t = mean[(c, b)]
        re = e / at(t, 1, -0.5)
        rp = p / at(t, 2, None)
        print(f"{c:<18} {b:>6.0f} {t:>8.2f} {e:>9.5f} {p:>7.4f} {re:>28.2f} {rp:>28.2f}")
