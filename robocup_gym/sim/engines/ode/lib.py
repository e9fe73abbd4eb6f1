"""A small ctypes binding of the Open Dynamics Engine (ODE), the engine rcssserver3d runs on.

Only what :mod:`robocup_gym.sim.engines.ode.world` needs: a world, bodies with masses, hinge joints
with
their motor/stop parameters, box/sphere/capsule/plane geoms, ``dCollide`` and contact joints. ODE
is not a Python package: it is the system library ``libode`` (Debian/Ubuntu: ``apt-get install
libode8``; rcssserver3d 0.7.3 was measured on ODE 0.16.2 in double precision, which is what
Debian 12 ships). ``ROBOCUP_GYM_LIBODE`` may name the library file explicitly.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os
from functools import cache

dReal = ctypes.c_double  # noqa: N816 (ODE's own type names)
dID = ctypes.c_void_p  # noqa: N816
Vec4 = dReal * 4
Mat3 = dReal * 12
"""ODE's 3×3 rotation matrix, stored row by row with 4 entries per row."""

# dSurfaceParameters.mode flags (ode/contact.h)
CONTACT_BOUNCE = 0x004
CONTACT_SOFT_ERP = 0x008
CONTACT_SOFT_CFM = 0x010
CONTACT_SLIP1 = 0x100
CONTACT_SLIP2 = 0x200

# joint parameters (ode/common.h, ODE 0.16: LoVel/HiVel sit between Vel and FMax)
PARAM_LO_STOP = 0
PARAM_HI_STOP = 1
PARAM_VEL = 2
PARAM_FMAX = 5
PARAM_FUDGE_FACTOR = 6
PARAM_BOUNCE = 7
PARAM_CFM = 8
PARAM_STOP_ERP = 9
PARAM_STOP_CFM = 10

INFINITY = float("inf")
"""ODE's ``dInfinity`` (IEEE infinity in this build)."""


class OdeUnavailableError(RuntimeError):
    """ODE (``libode``) is not installed, or is not the double-precision build SimSpark uses."""


class Mass(ctypes.Structure):
    """``dMass``: total mass, centre of mass and inertia tensor (3×4 rows)."""

    _fields_ = [("mass", dReal), ("c", Vec4), ("I", Mat3)]


class SurfaceParameters(ctypes.Structure):
    """``dSurfaceParameters`` (ODE 0.16 layout, with the rolling-friction fields)."""

    _fields_ = [
        ("mode", ctypes.c_int),
        ("mu", dReal),
        ("mu2", dReal),
        ("rho", dReal),
        ("rho2", dReal),
        ("rhoN", dReal),
        ("bounce", dReal),
        ("bounce_vel", dReal),
        ("soft_erp", dReal),
        ("soft_cfm", dReal),
        ("motion1", dReal),
        ("motion2", dReal),
        ("motionN", dReal),
        ("slip1", dReal),
        ("slip2", dReal),
    ]


class ContactGeom(ctypes.Structure):
    """``dContactGeom``: one contact point; the normal points into the first geom."""

    _fields_ = [
        ("pos", Vec4),
        ("normal", Vec4),
        ("depth", dReal),
        ("g1", dID),
        ("g2", dID),
        ("side1", ctypes.c_int),
        ("side2", ctypes.c_int),
    ]


class Contact(ctypes.Structure):
    """``dContact``: surface parameters + contact point, what a contact joint is made from."""

    _fields_ = [("surface", SurfaceParameters), ("geom", ContactGeom), ("fdir1", Vec4)]


class JointFeedback(ctypes.Structure):
    """``dJointFeedback``: force and torque a joint applied to its two bodies in the last step
    (world frame), filled by ``dWorldStep`` for joints given one with ``dJointSetFeedback``."""

    _fields_ = [("f1", Vec4), ("t1", Vec4), ("f2", Vec4), ("t2", Vec4)]


_SIGNATURES: dict[str, tuple] = {
    # name: (restype, argtypes)
    "dInitODE2": (ctypes.c_int, [ctypes.c_uint]),
    "dGetConfiguration": (ctypes.c_char_p, []),
    "dWorldCreate": (dID, []),
    "dWorldDestroy": (None, [dID]),
    "dWorldSetGravity": (None, [dID, dReal, dReal, dReal]),
    "dWorldSetERP": (None, [dID, dReal]),
    "dWorldSetCFM": (None, [dID, dReal]),
    "dWorldSetContactSurfaceLayer": (None, [dID, dReal]),
    "dWorldSetAutoDisableFlag": (None, [dID, ctypes.c_int]),
    "dWorldStep": (ctypes.c_int, [dID, dReal]),
    "dBodyCreate": (dID, [dID]),
    "dBodySetPosition": (None, [dID, dReal, dReal, dReal]),
    "dBodySetRotation": (None, [dID, Mat3]),
    "dBodySetLinearVel": (None, [dID, dReal, dReal, dReal]),
    "dBodySetAngularVel": (None, [dID, dReal, dReal, dReal]),
    "dBodyGetPosition": (ctypes.POINTER(dReal), [dID]),
    "dBodyGetRotation": (ctypes.POINTER(dReal), [dID]),
    "dBodyGetLinearVel": (ctypes.POINTER(dReal), [dID]),
    "dBodyGetQuaternion": (ctypes.POINTER(dReal), [dID]),
    "dBodySetQuaternion": (None, [dID, Vec4]),
    "dBodyGetAngularVel": (ctypes.POINTER(dReal), [dID]),
    "dBodySetMass": (None, [dID, ctypes.POINTER(Mass)]),
    "dBodyAddForce": (None, [dID, dReal, dReal, dReal]),
    "dBodyAddTorque": (None, [dID, dReal, dReal, dReal]),
    "dBodyEnable": (None, [dID]),
    "dBodyDisable": (None, [dID]),
    "dBodyIsEnabled": (ctypes.c_int, [dID]),
    "dMassSetZero": (None, [ctypes.POINTER(Mass)]),
    "dMassSetBoxTotal": (None, [ctypes.POINTER(Mass), dReal, dReal, dReal, dReal]),
    "dMassSetSphereTotal": (None, [ctypes.POINTER(Mass), dReal, dReal]),
    "dMassSetCapsuleTotal": (None, [ctypes.POINTER(Mass), dReal, ctypes.c_int, dReal, dReal]),
    "dJointCreateHinge": (dID, [dID, dID]),
    "dJointCreateContact": (dID, [dID, dID, ctypes.POINTER(Contact)]),
    "dJointAttach": (None, [dID, dID, dID]),
    "dJointSetFeedback": (None, [dID, ctypes.POINTER(JointFeedback)]),
    "dJointSetHingeAnchor": (None, [dID, dReal, dReal, dReal]),
    "dJointSetHingeAxis": (None, [dID, dReal, dReal, dReal]),
    "dJointSetHingeParam": (None, [dID, ctypes.c_int, dReal]),
    "dJointGetHingeParam": (dReal, [dID, ctypes.c_int]),
    "dJointGetHingeAngle": (dReal, [dID]),
    "dJointGetHingeAngleRate": (dReal, [dID]),
    "dJointGroupCreate": (dID, [ctypes.c_int]),
    "dJointGroupEmpty": (None, [dID]),
    "dCreateBox": (dID, [dID, dReal, dReal, dReal]),
    "dCreateSphere": (dID, [dID, dReal]),
    "dCreateCapsule": (dID, [dID, dReal, dReal]),
    "dCreatePlane": (dID, [dID, dReal, dReal, dReal, dReal]),
    "dGeomSetBody": (None, [dID, dID]),
    "dGeomSetPosition": (None, [dID, dReal, dReal, dReal]),
    "dGeomGetAABB": (None, [dID, ctypes.POINTER(dReal)]),
    "dGeomGetBody": (dID, [dID]),
    "dGeomDestroy": (None, [dID]),
    "dCollide": (ctypes.c_int, [dID, dID, ctypes.c_int, ctypes.POINTER(ContactGeom), ctypes.c_int]),
    # each world's own single-threaded step scheduler (OdeWorld); island threading is measured
    # by benchmarks/ode_threads.py and not used by the world (see there)
    "dThreadingAllocateSelfThreadedImplementation": (dID, []),
    "dThreadingAllocateMultiThreadedImplementation": (dID, []),
    "dThreadingAllocateThreadPool": (dID, [ctypes.c_uint, ctypes.c_size_t, ctypes.c_uint, dID]),
    "dThreadingThreadPoolServeMultiThreadedImplementation": (None, [dID, dID]),
    "dThreadingImplementationGetFunctions": (dID, [dID]),
    "dWorldSetStepThreadingImplementation": (dID, [dID, dID, dID]),
    "dWorldSetStepIslandsProcessingMaxThreadCount": (ctypes.c_uint, [dID, ctypes.c_uint]),
    "dThreadingImplementationShutdownProcessing": (None, [dID]),
    "dThreadingThreadPoolWaitIdleState": (None, [dID]),
    "dThreadingFreeThreadPool": (None, [dID]),
    "dThreadingFreeImplementation": (None, [dID]),
}


MIN_ABI = 8
"""The shared-library major version of ODE 0.16 (``libode.so.8``), the version rcssserver3d 0.7
is built against; older ODE has other structure layouts (contact, surface parameters)."""


def loaded_path(stem: str) -> str | None:
    """The file of the mapped shared library whose name starts with ``stem`` (Linux: from
    ``/proc/self/maps``), or ``None`` where that cannot be read."""
    try:
        with open("/proc/self/maps") as f:
            for line in f:
                name = line.rsplit(None, 1)[-1]
                if os.path.basename(name).startswith(stem + "."):
                    return name
    except OSError:
        return None
    return None


def abi_version(path: str) -> int | None:
    """The major version in a shared library's file name (``libode.so.8.1.0`` → 8,
    ``libode.8.dylib`` → 8), following symbolic links; ``None`` if it has none."""
    import re

    name = os.path.basename(os.path.realpath(path))
    m = re.search(r"\.so\.(\d+)", name) or re.search(r"\.(\d+)(?:\.\d+)*\.dylib$", name)
    return int(m.group(1)) if m else None


@cache
def load() -> ctypes.CDLL:
    """The initialised ODE library.

    Raises:
        OdeUnavailableError: when ``libode`` cannot be found or loaded, is a single-precision
            build (SimSpark's results are for double precision) or is older than ODE 0.16;
            the message says what was found and how to install the right one.
    """
    path = os.environ.get("ROBOCUP_GYM_LIBODE") or ctypes.util.find_library("ode") or "libode.so.8"
    try:
        lib = ctypes.CDLL(path)
    except OSError as e:
        raise OdeUnavailableError(
            f"the Open Dynamics Engine library could not be loaded ({path}: {e}); install it "
            "(Debian/Ubuntu: apt-get install libode8; macOS: brew install ode) or point "
            "ROBOCUP_GYM_LIBODE at libode.so, or use the MuJoCo engine (engine='mujoco')"
        ) from e
    for name, (restype, argtypes) in _SIGNATURES.items():
        fn = getattr(lib, name)
        fn.restype = restype
        fn.argtypes = argtypes
    config = lib.dGetConfiguration().decode()
    if "ODE_double_precision" not in config.split():
        raise OdeUnavailableError(
            f"{path} is not a double-precision ODE build (configuration: {config}); "
            "rcssserver3d's figures are for ODE in double precision. Install Debian/Ubuntu's "
            "libode8 (double precision) or build ODE 0.16 with --enable-double-precision, "
            "or use the MuJoCo engine (engine='mujoco')"
        )
    abi = abi_version(loaded_path("libode") or path)
    if abi is not None and abi < MIN_ABI:
        raise OdeUnavailableError(
            f"{loaded_path('libode') or path} is ODE with library ABI {abi}, older than ODE "
            f"0.16's ({MIN_ABI}, libode.so.{MIN_ABI}): its structures differ from the ones "
            "this binding and SimSpark use. Install ODE 0.16 (Debian/Ubuntu: apt-get install "
            "libode8; macOS: brew install ode) or point ROBOCUP_GYM_LIBODE at it"
        )
    lib.dInitODE2(0)
    return lib


def available() -> bool:
    """Whether a double-precision ODE can be loaded here."""
    try:
        load()
    except OdeUnavailableError:
        return False
    return True
