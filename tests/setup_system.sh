#!/usr/bin/env bash
# System packages the test suite uses beyond pip, installed where they are missing and this
# shell may (root with apt-get); otherwise says how to get them. Never fails: without them the
# checks that need them are skipped (ODE) or the world runs its NumPy path (C compiler), saying so.
#  * libode8: the Open Dynamics Engine (ODE 0.16 in double precision, the engine rcssserver3d
#    runs on) for the ODE reference checks (tests/sim/test_ode_reference.py,
#    benchmarks/ode_compare.py);
#  * a C compiler (gcc): the world compiles its per-cycle work on first use
#    (robocup_gym/sim/compiled.py; tests/sim/test_compiled.py checks it against the NumPy path).
missing=()
python3 -c "import ctypes.util, sys; sys.exit(0 if ctypes.util.find_library('ode') else 1)" \
  || missing+=(libode8)
command -v "${CC:-cc}" >/dev/null 2>&1 || missing+=(gcc libc6-dev)
[ ${#missing[@]} = 0 ] && exit 0
if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
  if apt-get install -y -qq "${missing[@]}" >/dev/null 2>&1 \
    || { apt-get update -qq >/dev/null 2>&1 && apt-get install -y -qq "${missing[@]}" >/dev/null 2>&1; }; then
    echo "setup_system: installed ${missing[*]}"
    exit 0
  fi
fi
echo "setup_system: missing ${missing[*]} (Debian/Ubuntu: apt-get install ${missing[*]})." \
  "Without libode the ODE reference checks are skipped (or set ROBOCUP_GYM_LIBODE to a" \
  "double-precision libode.so); without a C compiler the world runs its NumPy path (or set CC)."
exit 0
