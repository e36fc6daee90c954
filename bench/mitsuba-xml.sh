#!/usr/bin/env bash
# kalos against Mitsuba 3 on the same Mitsuba XML files (scenes/mitsuba/*.xml and, once
# fetched, scenes/mitsuba/public/*.xml by default):
# mean ratio and per-pixel RMSE against a Mitsuba reference at two spp counts, and
# side-by-side PNGs (reference | kalos) in docs/results/mitsuba-xml/.
#
# Needs: target/release/kalos (cargo build --release) and Mitsuba from bench/mitsuba-setup.sh.
# Environment overrides: RES (128)  SPP ("16 256")  REF_SPP (8192)
#   MITSUBA_VENV (/tmp/mitsuba)  LIBLLVM_PATH (/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

RES=${RES:-128}
SPP=${SPP:-"16 256"}
REF_SPP=${REF_SPP:-8192}
MITSUBA_VENV=${MITSUBA_VENV:-/tmp/mitsuba}
export DRJIT_LIBLLVM_PATH=${LIBLLVM_PATH:-/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1}

[[ -x target/release/kalos ]] || { echo "mitsuba-xml: build kalos first: cargo build --release" >&2; exit 1; }
[[ -x "$MITSUBA_VENV/bin/python" ]] || { echo "mitsuba-xml: no Mitsuba venv at $MITSUBA_VENV: run bench/mitsuba-setup.sh" >&2; exit 1; }

# The public scenes (Sionna RT's, from PyPI) are fetched, not committed:
# python3 scenes/mitsuba/fetch_public.py writes scenes/mitsuba/public/*.xml.
if [[ $# -gt 0 ]]; then
    scenes=("$@")
else
    scenes=(scenes/mitsuba/*.xml)
    if compgen -G "scenes/mitsuba/public/*.xml" >/dev/null; then
        scenes+=(scenes/mitsuba/public/*.xml)
    else
        echo "mitsuba-xml: no public scenes: python3 scenes/mitsuba/fetch_public.py fetches them" >&2
    fi
fi
# shellcheck disable=SC2086
exec "$MITSUBA_VENV/bin/python" bench/mitsuba-xml.py "${scenes[@]}" \
    --res "$RES" --spp $SPP --ref-spp "$REF_SPP"
