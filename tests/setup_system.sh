#!/usr/bin/env bash
# System packages RoboCup Gym uses beyond pip, installed where they are missing and this shell
# may (root, or password-less sudo, with apt-get); otherwise says how to get them. Never fails:
# the library then says what is missing when it is used.
#  * libode8: the Open Dynamics Engine 0.16 in double precision, the engine rcssserver3d runs
#    on and the default physics engine of RoboCup Gym (engine="ode"); without it only
#    engine="mujoco" works, and the ODE tests are skipped, saying so;
#  * a C compiler (gcc): both engines compile their per-cycle loops on first use
#    (robocup_gym/sim/compiled.py); without one they run the same work in Python/NumPy.
missing=()
python3 -c "import ctypes.util, sys; sys.exit(0 if ctypes.util.find_library('ode') else 1)" \
  || missing+=(libode8)
command -v "${CC:-cc}" >/dev/null 2>&1 || missing+=(gcc libc6-dev)
[ ${#missing[@]} = 0 ] && exit 0
if command -v apt-get >/dev/null 2>&1; then
  as_root=()
  if [ "$(id -u)" != 0 ]; then
    if command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then as_root=(sudo -n); else as_root=(false); fi
  fi
  if "${as_root[@]}" apt-get install -y -qq "${missing[@]}" >/dev/null 2>&1 \
    || { "${as_root[@]}" apt-get update -qq >/dev/null 2>&1 \
         && "${as_root[@]}" apt-get install -y -qq "${missing[@]}" >/dev/null 2>&1; }; then
    echo "setup_system: installed ${missing[*]}"
    exit 0
  fi
fi
echo "setup_system: missing ${missing[*]}; install them (Debian/Ubuntu: sudo apt-get install" \
  "${missing[*]}; macOS: brew install ode). Without libode the default engine (SimSpark's" \
  "physics on ODE) is unavailable and says so: use engine='mujoco' (--engine mujoco), or set" \
  "ROBOCUP_GYM_LIBODE to a double-precision libode.so. Without a C compiler the engines run" \
  "their per-cycle work in Python/NumPy (or set CC)."
exit 0
