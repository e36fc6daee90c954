#!/usr/bin/env bash
# Install Mitsuba 3 (llvm_ad_rgb + scalar_rgb variants) as a peer renderer for benchmarks and
# reference images. Idempotent: every step is skipped when already done.
# Follows /work/shared/bench/mitsuba/README.md.
#
# Environment overrides:
#   MITSUBA_VENV   virtualenv to create/use        (default /tmp/mitsuba)
#   LIBLLVM_PATH   libLLVM that Dr.Jit should load (default /usr/lib/x86_64-linux-gnu/libLLVM.so.19.1)
#   PYTHON         python used to create the venv  (default python3)
#
# Afterwards use:  export DRJIT_LIBLLVM_PATH=$LIBLLVM_PATH ; $MITSUBA_VENV/bin/python ...
set -euo pipefail

MITSUBA_VENV=${MITSUBA_VENV:-/tmp/mitsuba}
LIBLLVM_PATH=${LIBLLVM_PATH:-/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1}
PYTHON=${PYTHON:-python3}

die() { echo "mitsuba-setup: ERROR: $*" >&2; exit 1; }
log() { echo "mitsuba-setup: $*"; }

# 1. LLVM shared library for Dr.Jit's LLVM backend
if [[ -f "$LIBLLVM_PATH" ]]; then
    log "libLLVM present: $LIBLLVM_PATH (skip apt)"
else
    command -v apt-get >/dev/null || die "$LIBLLVM_PATH missing and apt-get not available; install LLVM 19 and set LIBLLVM_PATH"
    SUDO=""
    if [[ $(id -u) -ne 0 ]]; then
        command -v sudo >/dev/null || die "need root (or sudo) to apt-get install libllvm19"
        SUDO=sudo
    fi
    log "installing libllvm19 via apt-get"
    $SUDO apt-get update || die "apt-get update failed"
    $SUDO apt-get install -y libllvm19 || die "apt-get install -y libllvm19 failed"
    [[ -f "$LIBLLVM_PATH" ]] || die "libllvm19 installed but $LIBLLVM_PATH not found (set LIBLLVM_PATH to the installed libLLVM*.so)"
fi

# 2. Python virtualenv with mitsuba + numpy
if [[ -x "$MITSUBA_VENV/bin/python" ]]; then
    log "venv present: $MITSUBA_VENV"
else
    command -v "$PYTHON" >/dev/null || die "$PYTHON not found"
    log "creating venv $MITSUBA_VENV"
    "$PYTHON" -m venv "$MITSUBA_VENV" || die "'$PYTHON -m venv $MITSUBA_VENV' failed (is the python venv module installed?)"
fi
if "$MITSUBA_VENV/bin/python" -c 'import mitsuba, numpy' 2>/dev/null; then
    log "mitsuba and numpy already installed in $MITSUBA_VENV (skip pip)"
else
    log "pip install mitsuba numpy"
    "$MITSUBA_VENV/bin/pip" install mitsuba numpy || die "pip install mitsuba numpy failed"
fi

# 3. Smoke test: both variants load and the LLVM JIT runs a kernel
export DRJIT_LIBLLVM_PATH="$LIBLLVM_PATH"
out=$("$MITSUBA_VENV/bin/python" - <<'EOF' 2>&1
import mitsuba as mi, drjit as dr
mi.set_variant('scalar_rgb')
mi.set_variant('llvm_ad_rgb')
x = dr.llvm.Float(1, 2, 3) * 2
assert list(x) == [2, 4, 6], x
print(f'mitsuba {mi.__version__}, drjit {dr.__version__}, {dr.thread_count()} threads')
EOF
) || die "smoke test failed (DRJIT_LIBLLVM_PATH=$LIBLLVM_PATH):
$out"
log "OK: $out"
echo "export DRJIT_LIBLLVM_PATH=$LIBLLVM_PATH   # then run $MITSUBA_VENV/bin/python"
