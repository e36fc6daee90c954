#!/usr/bin/env python3
"""Equal-time ratios from a kalos experiment's results.csv (equal-spp budgets).

Usage: python3 docs/results/dtf_equal_time.py RESULTS.csv [BASELINE_CONFIG=path] [TIME_RATIO]

With TIME_RATIO (one number, or per budget "64:1.2,256:1.1"; the config's wall-clock time over the baseline's at equal spp, measured
side by side by time_ab.py or dtf_time_ab.py), the baseline's error at equal time is read off its
error-versus-*spp* curve at spp x TIME_RATIO instead: on a shared machine the seconds of
runs made one after another differ with the load more than the methods do.
Without it:

Per (config, budget), averaged over the seeds: RMSE, perceptual share and seconds. The
baseline's error *at the config's own time* is read off the baseline's measured
error-versus-time curve, interpolated linearly in log-log between its budgets (beyond the
ends: RMSE extrapolated with the Monte Carlo slope -1/2, the perceptual share with the
nearest segment's slope). The ratios printed are config / baseline at equal time."""
import csv, math, sys
from collections import defaultdict

rows = list(csv.DictReader(open(sys.argv[1])))
base = sys.argv[2] if len(sys.argv) > 2 else "path"
# TIME_RATIO: one number, or per budget "64:1.2,256:1.1,1024:1.05"
tr_arg = sys.argv[3] if len(sys.argv) > 3 else None
time_ratio = None if tr_arg is None else (
    {float(k): float(v) for k, v in (w.split(":") for w in tr_arg.split(","))}
    if ":" in tr_arg else defaultdict(lambda: float(tr_arg)))
acc = defaultdict(lambda: [0.0, 0.0, 0.0, 0])
lum = defaultdict(list)
order = []
for r in rows:
    k = (r["config"], float(r["budget"]))
    if k[0] not in order:
        order.append(k[0])
    lum[k].append(float(r["luminance_ratio"]))
    a = acc[k]
    a[0] += float(r["rmse"]); a[1] += float(r["perceptual_share"]); a[2] += float(r["seconds"]); a[3] += 1
mean = {k: (v[0] / v[3], v[1] / v[3], v[2] / v[3]) for k, v in acc.items()}
if time_ratio is None:
    curve = sorted((t, e, p) for (c, _), (e, p, t) in mean.items() if c == base)
else:
    curve = sorted((b, e, p) for (c, b), (e, p, t) in mean.items() if c == base)


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


print(f"| config | spp | seeds | seconds | RMSE | perceptual | image mean / reference, min..max over seeds "
      f"| RMSE vs {base} @ equal time | perceptual vs {base} @ equal time |")
print("|---|---|---|---|---|---|---|---|---|")
for c in order:
    for b in sorted({k[1] for k in mean if k[0] == c}):
        e, p, t = mean[(c, b)]
        x = t if time_ratio is None else b * (1.0 if c == base else time_ratio[b])
        re = e / at(x, 1, -0.5)
        rp = p / at(x, 2, None)
        lo, hi = min(lum[(c, b)]), max(lum[(c, b)])
        print(f"| {c} | {b:.0f} | {len(lum[(c, b)])} | {t:.2f} | {e:.5f} | {p:.1%} | {lo:.4f}..{hi:.4f} "
              f"| {re:.2f} | {rp:.2f} |")
