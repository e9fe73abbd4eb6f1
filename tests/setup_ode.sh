#!/usr/bin/env bash
# Makes the Open Dynamics Engine (the system library libode, ODE 0.16 in double precision: the
# engine rcssserver3d runs on) available for the ODE reference checks (tests/sim/test_ode_reference.py,
# benchmarks/ode_compare.py). Installs Debian's libode8 when it is missing and this shell may
# (root with apt-get); otherwise says how to get it. Never fails: without ODE those checks are
# skipped, saying so.
if python3 -c "import ctypes.util, sys; sys.exit(0 if ctypes.util.find_library('ode') else 1)"; then
  exit 0
fi
if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
  if apt-get install -y -qq libode8 >/dev/null 2>&1 \
    || { apt-get update -qq >/dev/null 2>&1 && apt-get install -y -qq libode8 >/dev/null 2>&1; }; then
    echo "setup_ode: installed libode8"
    exit 0
  fi
fi
echo "setup_ode: no libode here; the ODE reference checks will be skipped" \
  "(Debian/Ubuntu: apt-get install libode8; or set ROBOCUP_GYM_LIBODE to a double-precision libode.so)"
exit 0
