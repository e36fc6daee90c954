#!/usr/bin/env bash
# DTF with a prescribed relative error eps_r = 0.1, 0.03, 0.01 on the Cornell box (32x32, so
# that eps_r = 0.01 stays affordable): the error against a high-spp reference must keep falling.
# EPS="0.1 0.03" runs a subset.
set -euo pipefail
cd "$(dirname "$0")/../.."
K=target/release/kalos
out=docs/results/eps-series
mkdir -p $out
$K render cornell --res 32x32 --spp 65536 --seed 2718281828 -q -o $out/reference.exr
echo "eps_r,avg_spp,seconds,rmse,relmse,perceptual_share"
for eps in ${EPS:-0.1 0.03 0.01}; do
  $K render cornell --res 32x32 --method dtf --dtf-n 32 --dtf-eps $eps -q -o $out/dtf-$eps.exr --stats $out/dtf-$eps.json
  m=$($K compare $out/dtf-$eps.exr $out/reference.exr --json)
  python3 - "$eps" "$out/dtf-$eps.json" "$m" <<'PY'
import json, sys
s = json.load(open(sys.argv[2])); m = json.loads(sys.argv[3])
print(f"{sys.argv[1]},{s['spp']},{s['seconds']:.2f},{m['rmse']:.6f},{m['relmse']:.6f},{m['perceptual_share']:.4f}")
PY
done
