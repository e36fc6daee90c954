#!/usr/bin/env bash
# Throughput of kalos vs Mitsuba 3 (llvm_ad_rgb) on the Cornell box, same machine, back to back.
# Same work in both: 256x256, fixed depth 8 (Mitsuba max_depth counts segments), no roulette.
# Each repetition runs Mitsuba then kalos; the final line is the median of per-pair ratios.
#
# Needs: an already built target/release/kalos (cargo build --release) and Mitsuba installed by
# bench/mitsuba-setup.sh.
#
# Environment overrides:
#   SPP (256)  REPS (3)  THREADS (2: kalos --threads, and Mitsuba's Dr.Jit thread count when the
#   machine has more cores than that; Dr.Jit deadlocks with 1, so 1 leaves Mitsuba at its default)
#   MITSUBA_VENV (/tmp/mitsuba)  LIBLLVM_PATH (/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1)
#   MITSUBA_DIR (/work/shared/bench/mitsuba)  KALOS (target/release/kalos)
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")/.."   # repository root

SPP=${SPP:-256}
REPS=${REPS:-3}
THREADS=${THREADS:-2}
MITSUBA_VENV=${MITSUBA_VENV:-/tmp/mitsuba}
LIBLLVM_PATH=${LIBLLVM_PATH:-/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1}
MITSUBA_DIR=${MITSUBA_DIR:-/work/shared/bench/mitsuba}
KALOS=${KALOS:-target/release/kalos}
MI_OUT=/tmp/mitsuba-bench.exr
K_OUT=/tmp/kalos-bench.exr
K_STATS=/tmp/kalos-stats.json

die() { echo "compare-mitsuba: ERROR: $*" >&2; exit 1; }

[[ -x "$KALOS" ]] || die "$KALOS not found or not executable; build it first: cargo build --release"
[[ -x "$MITSUBA_VENV/bin/python" ]] || die "no Mitsuba venv at $MITSUBA_VENV; run bench/mitsuba-setup.sh"
[[ -f "$LIBLLVM_PATH" ]] || die "$LIBLLVM_PATH missing; run bench/mitsuba-setup.sh"
[[ -f "$MITSUBA_DIR/render_obj.py" && -f "$MITSUBA_DIR/cornell-box.obj" ]] \
    || die "render_obj.py / cornell-box.obj not found in $MITSUBA_DIR"
export DRJIT_LIBLLVM_PATH="$LIBLLVM_PATH"

# JSON field extraction: jq if present, else python3 (json module). Searches the whole document
# for the first occurrence of the key, so nesting in kalos' stats file does not matter.
if command -v jq >/dev/null; then
    json_get() { jq -er --arg k "$1" 'first(.. | objects | select(has($k)) | .[$k])'; }
elif command -v python3 >/dev/null; then
    json_get() {
        python3 -c '
import json, sys
def find(o, k):
    if isinstance(o, dict):
        if k in o: return o[k]
        o = list(o.values())
    if isinstance(o, list):
        for v in o:
            r = find(v, k)
            if r is not None: return r
    return None
r = find(json.load(sys.stdin), sys.argv[1])
if r is None: sys.exit(1)
print(r)' "$1"
    }
else
    die "need jq or python3 to parse JSON"
fi

# Mitsuba uses all cores by default; match kalos' thread count when the machine has more.
MI_THREADS=""
if [[ $THREADS -ge 2 && $(nproc) -gt $THREADS ]]; then MI_THREADS=$THREADS; fi

run_mitsuba() {
    local args=(cornell-box.obj "$MI_OUT" --spp "$SPP" --res 256 256 --max-depth 8 --rr-depth 1000)
    (
        cd "$MITSUBA_DIR"
        if [[ -n $MI_THREADS ]]; then
            "$MITSUBA_VENV/bin/python" -c '
import sys, runpy, drjit as dr
dr.set_thread_count(int(sys.argv[1]))
sys.argv = ["render_obj.py"] + sys.argv[2:]
runpy.run_path("render_obj.py", run_name="__main__")' "$MI_THREADS" "${args[@]}"
        else
            "$MITSUBA_VENV/bin/python" render_obj.py "${args[@]}"
        fi
    ) | grep '^{' | tail -n 1 | json_get paths_per_s
}

run_kalos() {
    rm -f "$K_STATS"
    "$KALOS" render cornell --spp "$SPP" --max-depth 8 --rr off --threads "$THREADS" --quiet \
        --stats "$K_STATS" -o "$K_OUT" >&2 || die "kalos render failed"
    [[ -s "$K_STATS" ]] || die "kalos wrote no stats file $K_STATS"
    json_get paths_per_second < "$K_STATS" || die "no paths_per_second in $K_STATS"
}

echo "compare-mitsuba: Cornell 256x256, spp $SPP, depth 8, no RR, kalos --threads $THREADS," \
     "mitsuba threads ${MI_THREADS:-default($(nproc))}, $REPS reps; $(nproc) cores, load$(uptime | sed 's/.*load average://')"
ratios=(); kv=(); mv=()
for ((i = 1; i <= REPS; i++)); do
    m=$(run_mitsuba) || die "mitsuba render failed (rep $i)"
    [[ -n $m ]] || die "mitsuba printed no paths_per_s (rep $i)"
    k=$(run_kalos) || exit 1
    r=$(awk -v k="$k" -v m="$m" 'BEGIN { printf "%.4f", k / m }')
    printf 'rep %d: mitsuba %.4g paths/s, kalos %.4g paths/s, ratio %s\n' "$i" "$m" "$k" "$r"
    ratios+=("$r"); kv+=("$k"); mv+=("$m")
done

sci() { printf '%.2g' "$1" | sed -E 's/e\+?0*([0-9])/e\1/; s/e-0*([0-9])/e-\1/'; }
median() { printf '%s\n' "$@" | sort -g | awk '{ a[NR] = $1 } END { print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2 }'; }
printf 'ratio kalos/mitsuba paths_per_second: %.2f (kalos %s, mitsuba %s)\n' \
    "$(median "${ratios[@]}")" "$(sci "$(median "${kv[@]}")")" "$(sci "$(median "${mv[@]}")")"
