#!/usr/bin/env bash
# Throughput of kalos vs Mitsuba 3 on the same triangles and the same work, same machine, back
# to back. Each repetition runs Mitsuba then kalos; a case's line is the median of its per-pair
# ratios (kalos paths/s over Mitsuba paths/s), beside both renderers' medians and image means.
#
# Cases (CASES, space-separated; default: the first one):
#   cornell     Cornell box 256x256, fixed depth 8 (Mitsuba max_depth counts segments), no
#               roulette, kalos --threads THREADS against Mitsuba VARIANT (llvm_ad_rgb)
#   cornell-1   the same on one core against scalar_rgb: both pinned to CPU 0 with taskset, two
#               threads each (Dr.Jit deadlocks with one; kalos' image does not depend on its
#               thread count), so that other jobs on that core take the same share from both
#   cornell-rr  roulette on, both at their defaults: Mitsuba rr_depth 5 against kalos' default
#               roulette, unlimited depth (max_depth -1) in both
#   mesh        a 1M-triangle scene: a closed room whose floor is a height field of 999,698
#               triangles (bench/heightfield.py, written by this script; diffuse only, so both
#               render the same BSDFs), 128x128, depth 8, no roulette
#   mesh-1      the mesh on one core against scalar_rgb (pinned as cornell-1)
#   open        an open 1M-triangle scene: the same height field alone under one light (no walls;
#               bench/heightfield.py --open, written by this script), seen from above at an angle,
#               128x128, depth 8, no roulette: most paths leave after a bounce or two, and the
#               camera and shadow rays are coherent
#   open-1      the open height field on one core against scalar_rgb (pinned as cornell-1)
#   room        an interior of the size users render: assets/scenes/room.obj (4,226 triangles:
#               walls, furniture, four ceiling lights), its materials made diffuse (Kd, Ke; the
#               floor's Phong lobe dropped, as render_obj.py reads only Kd and Ke) in a copy under
#               /tmp, 256x256, depth 8, no roulette, from kalos' default camera in the room
#   room-1      the room on one core against scalar_rgb (pinned as cornell-1)
#   all         all of the above
#   two-threads the four two-thread cases against llvm_ad_rgb: cornell room mesh open
#
# Before the figures it prints the CPU model, its vector extensions and the SIMD path kalos
# chose (its `--stats` field `simd`; KALOS_SIMD=sse2 forces the baseline path).
#
# Needs: an already built target/release/kalos (cargo build --release) and Mitsuba installed by
# bench/mitsuba-setup.sh.
#
# Environment overrides:
#   CASES (cornell)  SPP (256; the mesh cases use SPP_MESH, 16; the open ones SPP_OPEN, 128)  REPS (3)  THREADS (2: kalos
#   --threads, and Mitsuba's Dr.Jit thread count when the machine has more cores than that)
#   VARIANT (llvm_ad_rgb)  VARIANT_1 (the one-core cases' Mitsuba variant: scalar_rgb)  MESH (/tmp/kalos-bench-heightfield.obj)
#   OPEN (/tmp/kalos-bench-open.obj)
#   MITSUBA_VENV (/tmp/mitsuba)  LIBLLVM_PATH (/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1)
#   MITSUBA_DIR (/work/shared/bench/mitsuba)  KALOS (target/release/kalos)
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")/.."   # repository root

CASES=${CASES:-cornell}
SPP=${SPP:-256}
SPP_MESH=${SPP_MESH:-16}
SPP_OPEN=${SPP_OPEN:-128}
REPS=${REPS:-3}
THREADS=${THREADS:-2}
VARIANT=${VARIANT:-llvm_ad_rgb}
VARIANT_1=${VARIANT_1:-scalar_rgb}
MESH=${MESH:-/tmp/kalos-bench-heightfield.obj}
OPEN=${OPEN:-/tmp/kalos-bench-open.obj}
MITSUBA_VENV=${MITSUBA_VENV:-/tmp/mitsuba}
LIBLLVM_PATH=${LIBLLVM_PATH:-/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1}
MITSUBA_DIR=${MITSUBA_DIR:-/work/shared/bench/mitsuba}
KALOS=${KALOS:-target/release/kalos}
MI_OUT=/tmp/mitsuba-bench.exr
K_OUT=/tmp/kalos-bench.exr
K_STATS=/tmp/kalos-stats.json
MESH_CAM=(0 1.3 0.95 0 0 -0.3 0 1 0 60)
OPEN_CAM=(0 2.6 2.6 0 0 0 0 1 0 45)
ROOM_DIR=/tmp/kalos-bench-room
ROOM=$ROOM_DIR/room.obj
ROOM_CAM=(5.6786 1.5 3.2143 4.6786 1.5 3.2143 0 1 0 60)

die() { echo "compare-mitsuba: ERROR: $*" >&2; exit 1; }

[[ -x "$KALOS" ]] || die "$KALOS not found or not executable; build it first: cargo build --release"
[[ -x "$MITSUBA_VENV/bin/python" ]] || die "no Mitsuba venv at $MITSUBA_VENV; run bench/mitsuba-setup.sh"
[[ -f "$LIBLLVM_PATH" ]] || die "$LIBLLVM_PATH missing; run bench/mitsuba-setup.sh"
[[ -f "$MITSUBA_DIR/render_obj.py" && -f "$MITSUBA_DIR/cornell-box.obj" ]] \
    || die "render_obj.py / cornell-box.obj not found in $MITSUBA_DIR"
export DRJIT_LIBLLVM_PATH="$LIBLLVM_PATH"
[[ $CASES == all ]] && CASES="cornell cornell-1 cornell-rr mesh mesh-1 room room-1 open open-1"
[[ $CASES == two-threads ]] && CASES="cornell room mesh open"
for c in $CASES; do
    case $c in cornell | cornell-1 | cornell-rr | mesh | mesh-1 | room | room-1 | open | open-1) ;;
    *) die "unknown case '$c' in CASES (cornell, cornell-1, cornell-rr, mesh, mesh-1, room, room-1, open, open-1, all, two-threads)" ;;
    esac
done
if [[ " $CASES " == *"-1 "* ]]; then
    command -v taskset >/dev/null || die "the one-core cases need taskset (util-linux)"
fi

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

# The machine, as the figures need it.
cpu_model=$(grep -m1 '^model name' /proc/cpuinfo | sed 's/.*: //')
cpu_flags=$(grep -m1 '^flags' /proc/cpuinfo | tr ' ' '\n' \
    | grep -xE 'sse4_2|avx|avx2|fma|avx512f|avx512vl|avx512bw|avx512dq' | tr '\n' ' ')
echo "compare-mitsuba: CPU $cpu_model, $(nproc) cores, vector extensions: ${cpu_flags:-none beyond sse2}"
echo "compare-mitsuba: load$(uptime | sed 's/.*load average://') (a shared machine makes pairs noisy)"

if [[ " $CASES " == *" mesh"* && ! -s $MESH ]]; then
    echo "compare-mitsuba: generating $MESH (bench/heightfield.py)" >&2
    "$MITSUBA_VENV/bin/python" bench/heightfield.py "$MESH" 1000000 || die "could not generate $MESH"
fi
if [[ " $CASES " == *" open"* && ! -s $OPEN ]]; then
    echo "compare-mitsuba: generating $OPEN (bench/heightfield.py --open)" >&2
    "$MITSUBA_VENV/bin/python" bench/heightfield.py "$OPEN" 1000000 --open || die "could not generate $OPEN"
fi

if [[ " $CASES " == *" room"* ]]; then
    mkdir -p "$ROOM_DIR" || die "could not create $ROOM_DIR"
    cp assets/scenes/room.obj "$ROOM" || die "assets/scenes/room.obj not found (run from the repository)"
    grep -vE '^[[:space:]]*(Ks|Ns|illum)[[:space:]]' assets/scenes/room.mtl >"$ROOM_DIR/room.mtl" \
        || die "could not write $ROOM_DIR/room.mtl"
fi

# run_mitsuba OBJ SPP RES MAX_DEPTH RR_DEPTH VARIANT THREADS PIN -> "paths_per_s mean"
run_mitsuba() {
    local obj=$1 spp=$2 res=$3 depth=$4 rr=$5 variant=$6 threads=$7 pin=$8
    local args=("$obj" "$MI_OUT" --spp "$spp" --res "$res" "$res" --max-depth "$depth"
        --rr-depth "$rr" --variant "$variant")
    [[ $obj == "$MESH" ]] && args+=(--cam "${MESH_CAM[@]}")
    [[ $obj == "$ROOM" ]] && args+=(--cam "${ROOM_CAM[@]}")
    [[ $obj == "$OPEN" ]] && args+=(--cam "${OPEN_CAM[@]}")
    # Match kalos' thread count when the machine has more cores. Dr.Jit deadlocks with one
    # thread (and so when pinned to one core with its default count), so one core is two
    # Dr.Jit threads pinned to CPU 0 by taskset.
    local pre=() mt=""
    if [[ $pin == 1 ]]; then
        pre=(taskset -c 0) mt=2
    elif [[ $threads -ge 2 && $(nproc) -gt $threads ]]; then
        mt=$threads
    fi
    local line
    line=$(
        cd "$MITSUBA_DIR"
        if [[ -n $mt ]]; then
            "${pre[@]}" "$MITSUBA_VENV/bin/python" -c '
import sys, runpy, drjit as dr
dr.set_thread_count(int(sys.argv[1]))
sys.argv = ["render_obj.py"] + sys.argv[2:]
runpy.run_path("render_obj.py", run_name="__main__")' "$mt" "${args[@]}"
        else
            "${pre[@]}" "$MITSUBA_VENV/bin/python" render_obj.py "${args[@]}"
        fi | grep '^{' | tail -n 1
    )
    [[ -n $line ]] || return 1
    echo "$(json_get paths_per_s <<<"$line") $(json_get mean <<<"$line")"
}

# run_kalos SCENE SPP RES MAX_DEPTH RR THREADS PIN [extra...] -> "paths_per_second mean simd"
run_kalos() {
    local scene=$1 spp=$2 res=$3 depth=$4 rr=$5 threads=$6 pin=$7
    shift 7
    local pre=()
    [[ $pin == 1 ]] && pre=(taskset -c 0)
    # The same work as Mitsuba's path integrator with its independent sampler: the path tracer
    # rendered plainly (not the automatic method's pilots and filtering) with independent numbers.
    local args=(render "$scene" --method plain --integrator path --sampler random --spp "$spp"
        --res "${res}x${res}" --max-depth "$depth" --threads "$threads" --quiet --stats "$K_STATS"
        -o "$K_OUT" "$@")
    [[ $rr == off ]] && args+=(--rr off)
    rm -f "$K_STATS"
    "${pre[@]}" "$KALOS" "${args[@]}" >&2 || return 1
    [[ -s "$K_STATS" ]] || return 1
    local mean
    mean=$(json_get mean_rgb <"$K_STATS" | tr -d '[] \n' | awk -F, '{ printf "%.6g", ($1 + $2 + $3) / 3 }')
    echo "$(json_get paths_per_second <"$K_STATS") $mean $(json_get simd <"$K_STATS")"
}

sci() { printf '%.3g' "$1"; }
median() { printf '%s\n' "$@" | sort -g | awk '{ a[NR] = $1 } END { print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2 }'; }

summary=()
for c in $CASES; do
    threads=$THREADS pin=0 variant=$VARIANT depth=8 mi_rr=1000 k_rr=off
    case $c in
        cornell*) obj=cornell-box.obj scene=cornell spp=$SPP res=256 ;;
        mesh*) obj=$MESH scene=$MESH spp=$SPP_MESH res=128 ;;
        room*) obj=$ROOM scene=$ROOM spp=$SPP res=256 ;;
        open*) obj=$OPEN scene=$OPEN spp=$SPP_OPEN res=128 ;;
    esac
    kextra=()
    [[ $c == mesh* ]] && kextra=(--camera "$(IFS=,; echo "${MESH_CAM[*]}")")
    [[ $c == room* ]] && kextra=(--camera "$(IFS=,; echo "${ROOM_CAM[*]}")")
    [[ $c == open* ]] && kextra=(--camera "$(IFS=,; echo "${OPEN_CAM[*]}")")
    # One core: both pinned to CPU 0 with two threads each (Dr.Jit deadlocks with one), so
    # that on a loaded machine the scheduler gives both the same share of that core.
    [[ $c == *-1 ]] && threads=2 pin=1 variant=$VARIANT_1
    [[ $c == cornell-rr ]] && depth=-1 mi_rr=5 k_rr=default
    roulette=off core=""
    if [[ $k_rr != off ]]; then roulette="on (mitsuba rr_depth $mi_rr, kalos default)"; fi
    if [[ $pin == 1 ]]; then core=", both on one core (taskset -c 0)"; fi
    desc="$c: ${res}x${res}, spp $spp, depth $depth, roulette $roulette,"
    desc+=" kalos --threads $threads vs mitsuba $variant$core"
    echo "$desc"
    ratios=() kv=() mv=() km="" mm="" simd=""
    for ((i = 1; i <= REPS; i++)); do
        read -r m mm < <(run_mitsuba "$obj" "$spp" "$res" "$depth" "$mi_rr" "$variant" "$threads" "$pin") \
            || die "mitsuba render failed ($c, rep $i)"
        read -r k km simd < <(run_kalos "$scene" "$spp" "$res" "$depth" "$k_rr" "$threads" "$pin" "${kextra[@]}") \
            || die "kalos render failed ($c, rep $i)"
        r=$(awk -v k="$k" -v m="$m" 'BEGIN { printf "%.4f", k / m }')
        printf '  rep %d: mitsuba %.4g paths/s, kalos (%s) %.4g paths/s, ratio %s\n' "$i" "$m" "$simd" "$k" "$r"
        ratios+=("$r"); kv+=("$k"); mv+=("$m")
    done
    line=$(printf '%-10s ratio kalos/mitsuba %.2f (kalos %s, mitsuba %s paths/s; kalos simd %s; image mean kalos %s, mitsuba %.6g)' \
        "$c" "$(median "${ratios[@]}")" "$(sci "$(median "${kv[@]}")")" "$(sci "$(median "${mv[@]}")")" "$simd" "$km" "$mm")
    echo "$line"
    summary+=("$line")
done
echo "summary ($cpu_model; ${cpu_flags:-sse2}):"
printf '  %s\n' "${summary[@]}"
