"""The ODE world's per-cycle loops in C (``ode_step.c``): drag, commands, contact generation,
reading the state, the foot sensors' sums, saving and restoring bodies, placing a robot.

In Python they make ~200 ctypes calls a cycle, which take as long as ODE's own ``dWorldStep``.
``ode_step.c`` makes the same ODE calls, with the same arguments in the same order, through
the function pointers of the ctypes binding (:mod:`robocup_gym.sim.engines.ode.lib`), so it needs
neither ODE's headers nor linking, and the results are bit-equal. It is built like the MuJoCo
world's compiled step (:mod:`robocup_gym.sim.compiled`: system C compiler, cached, the same
``ROBOCUP_GYM_COMPILED`` switch); where it cannot be built, :class:`OdeWorld
<robocup_gym.sim.engines.ode.world.OdeWorld>` runs the Python loops.
"""

from __future__ import annotations

import ctypes
from pathlib import Path

import numpy as np

from robocup_gym.sim import compiled
from robocup_gym.sim.engines.ode import lib as ode

SOURCE = Path(__file__).with_name("ode_step.c")
SANE_SPEED = 1e6
"""Largest linear (m/s) or angular (rad/s) velocity component of a sane body: beyond it (or at
NaN) the solver has blown up, and ODE's next step would abort the whole process."""
FUNCTIONS = (
    "dCollide",
    "dJointCreateContact",
    "dJointAttach",
    "dJointSetFeedback",
    "dBodyGetLinearVel",
    "dBodyGetAngularVel",
    "dBodyAddForce",
    "dBodyAddTorque",
    "dJointGetHingeAngle",
    "dJointSetHingeParam",
    "dBodyEnable",
    "dGeomGetAABB",
    "dBodyGetPosition",
    "dBodyGetRotation",
    "dJointGetHingeAngleRate",
    "dBodyGetQuaternion",
    "dBodyIsEnabled",
    "dBodySetPosition",
    "dBodySetQuaternion",
    "dBodySetLinearVel",
    "dBodySetAngularVel",
    "dBodyDisable",
    "dBodySetRotation",
)
"""The ODE functions ``ode_step.c`` calls, in the order of its ``ode_fns`` struct."""

_p = ctypes.c_void_p


class OdeFunctions(ctypes.Structure):
    """``ode_fns``: pointers to the ODE functions, taken from the ctypes binding."""

    _fields_ = [(name, _p) for name in FUNCTIONS]


def load() -> ctypes.CDLL:
    """The compiled helper (:func:`robocup_gym.sim.compiled.load_library` of ``ode_step.c``:
    built once per process; a failure is remembered too, :func:`compiled.forget
    <robocup_gym.sim.compiled.forget>` starts over).

    Raises:
        robocup_gym.sim.compiled.CompiledStepUnavailableError: it cannot be built or loaded.
    """
    return compiled.load_library(SOURCE, _configure)


def _configure(lib: ctypes.CDLL) -> None:
    lib.ode_sizeof_contact.restype = ctypes.c_int
    if lib.ode_sizeof_contact() != ctypes.sizeof(ode.Contact):
        raise compiled.CompiledStepUnavailableError(
            "ode_step.c's dContact and lib.py's Contact differ in size"
        )
    lib.ode_drag.argtypes = [_p, ctypes.c_int, _p, _p, ctypes.c_double]
    lib.ode_drag.restype = ctypes.c_int
    lib.ode_realise.argtypes = [_p, ctypes.c_int, _p, _p, _p, _p, _p, ctypes.c_int]
    lib.ode_realise.restype = None
    lib.ode_collide.argtypes = [_p, _p, _p, ctypes.c_int, _p, _p, _p, ctypes.c_int, _p, _p]
    lib.ode_collide.argtypes += [_p, _p, ctypes.c_int, _p, _p, _p, _p, ctypes.c_int]
    lib.ode_collide.restype = ctypes.c_int
    lib.ode_read.argtypes = [_p, ctypes.c_int, _p, _p, ctypes.c_int, _p, _p, _p, ctypes.c_double]
    lib.ode_read.restype = ctypes.c_int
    lib.ode_frp.argtypes = [ctypes.c_int, _p, _p, _p, _p, ctypes.c_int, _p]
    lib.ode_frp.restype = None
    lib.ode_bodies.argtypes = [_p, ctypes.c_int, _p, _p, ctypes.c_int]
    lib.ode_bodies.restype = None
    lib.ode_place.argtypes = [_p, ctypes.c_int, _p, _p, _p, ctypes.c_int, ctypes.c_int, _p]
    lib.ode_place.argtypes += [ctypes.c_int]
    lib.ode_place.restype = None


class FastLoops:
    """The C loops bound to one :class:`~robocup_gym.sim.engines.ode.world.OdeWorld`'s handles.

    Args:
        ode_lib: The world's ctypes ODE binding (its function pointers are passed to C).
        bodies: Every body that feels drag, with its ``(linear, angular)`` drag coefficients.
        robots: Per robot ``(body handles, joint handles, child body handles, (n, 2) limits
            rad, max speeds rad/s)``.
        world, group: The ODE world and its contact joint group.
        pairs: The world's collision pairs ``(g1, g2, b1, b2, surface, frp1, frp2)``.
        feedback: The world's ``dJointFeedback`` slots (one per sensed contact).
        max_contacts: Contacts per pair.
        slot_geoms: The geoms with an AABB slot (all but the ground plane).
        pair_slots: ``(n_pairs, 2)`` slot of each pair's geoms (-1: the ground plane).
        state: ``(bodies, state array (n, 18), joints, angles, rates)`` that :meth:`read`
            fills (``OdeWorld``'s state snapshot).
        sensed_out: ``(pair index array, position array (n, 3))`` that :meth:`collide` fills
            for the sensed contacts (the world's own arrays).
        hit: ``int32`` array, one entry per pair: :meth:`collide` writes its ``stamp`` into the
            entry of every pair that made a contact (the world's own array).
        frp: ``(side slots (n_pairs, 2) int32, sums (n_sensors, 8))``: the force sensor of each
            pair's two bodies (-1: none) and the array :meth:`frp` fills (the world's own).
        bound: A body whose position is this far (m) from the origin in a coordinate is not
            sane (:meth:`read` reports it).
    """

    def __init__(
        self,
        ode_lib,
        bodies,
        robots,
        world,
        group,
        pairs,
        feedback,
        max_contacts,
        slot_geoms,
        pair_slots,
        state,
        sensed_out,
        hit,
        frp,
        bound,
    ):
        self._lib = load()
        self._fns = OdeFunctions(
            *[ctypes.cast(getattr(ode_lib, name), _p).value for name in FUNCTIONS]
        )
        fns = ctypes.addressof(self._fns)
        n_bodies = len(bodies)
        self._bodies = (_p * n_bodies)(*[b for b, _ in bodies])
        self._coef = np.ascontiguousarray([c for _, c in bodies], dtype=float)
        self._drag_args = (
            fns,
            n_bodies,
            ctypes.addressof(self._bodies),
            compiled.address(self._coef),
            SANE_SPEED,
        )
        self._keep = []  # the arrays the per-robot arguments point into
        self._realise_args = []
        self._place_args = []
        for bodies_r, joints, child, limits, vmax in robots:
            b = (_p * len(bodies_r))(*bodies_r)
            j = (_p * len(joints))(*joints)
            c = (_p * len(child))(*child)
            lim = np.ascontiguousarray(limits, dtype=float)
            vm = np.ascontiguousarray(vmax, dtype=float)
            self._keep.append((b, j, c, lim, vm))
            self._place_args.append(
                (fns, len(bodies_r), ctypes.addressof(b), len(joints), ctypes.addressof(j))
            )
            self._realise_args.append(
                (
                    fns,
                    len(joints),
                    ctypes.addressof(j),
                    ctypes.addressof(c),
                    compiled.address(lim),
                    compiled.address(vm),
                )
            )
        n = len(pairs)
        self._pairs = (_p * (4 * n))(*[h for pair in pairs for h in pair[:4]])
        self._surfaces = (ode.SurfaceParameters * n)(*[pair[4] for pair in pairs])
        self._sensed = np.array([int(bool(p[5] or p[6])) for p in pairs], dtype=np.int32)
        self._buf = (ode.ContactGeom * max_contacts)()
        self._feedback = feedback
        self._out_pair, self._out_pos = sensed_out
        self._slot_geoms = (_p * len(slot_geoms))(*slot_geoms)
        self._pair_slots = np.ascontiguousarray(pair_slots, dtype=np.int32)
        self._aabb = np.zeros((len(slot_geoms), 6))
        bodies_all, out, joints_all, angles, rates = state
        self._read_bodies = (_p * len(bodies_all))(*bodies_all)
        self._read_joints = (_p * max(len(joints_all), 1))(*joints_all)
        self._read_args = (
            fns,
            len(bodies_all),
            ctypes.addressof(self._read_bodies),
            compiled.address(out),
            len(joints_all),
            ctypes.addressof(self._read_joints),
            compiled.address(angles),
            compiled.address(rates),
            float(bound),
        )
        self._bodies_args = (fns, len(bodies_all), ctypes.addressof(self._read_bodies))
        side_slot, sums = frp
        self._side_slot = np.ascontiguousarray(side_slot, dtype=np.int32)
        self._frp_args = (
            ctypes.addressof(feedback),
            compiled.address(self._out_pair),
            compiled.address(self._out_pos),
            compiled.address(self._side_slot),
            len(sums),
            compiled.address(sums),
        )
        self._collide_args = (
            fns,
            world,
            group,
            n,
            ctypes.addressof(self._pairs),
            ctypes.addressof(self._surfaces),
            compiled.address(self._sensed),
            max_contacts,
            ctypes.addressof(self._buf),
            ctypes.addressof(feedback),
            compiled.address(self._out_pair),
            compiled.address(self._out_pos),
            len(slot_geoms),
            ctypes.addressof(self._slot_geoms),
            compiled.address(self._pair_slots),
            compiled.address(self._aabb),
            compiled.address(hit),
        )
        self._hit = hit

    def read(self) -> int:
        """Fill the world's state snapshot (``OdeWorld._read_state``); returns the index of the
        first body that is not sane (position NaN or beyond ``bound``), else -1."""
        return self._lib.ode_read(*self._read_args)

    def save_bodies(self) -> np.ndarray:
        """The complete dynamic state of every body the state snapshot covers (position,
        quaternion, velocities, enabled; 14 numbers per body), for :meth:`restore_bodies`."""
        fns, nb, bodies = self._bodies_args
        saved = np.empty((nb, 14))
        self._lib.ode_bodies(fns, nb, bodies, compiled.address(saved), 1)
        return saved

    def restore_bodies(self, saved: np.ndarray) -> None:
        """Put back the state :meth:`save_bodies` returned (the same ODE calls as
        ``OdeWorld.sense_contacts``'s Python loop)."""
        fns, nb, bodies = self._bodies_args
        self._lib.ode_bodies(fns, nb, bodies, compiled.address(saved), 0)

    def place(self, robot: int, positions: np.ndarray, rotations: np.ndarray, asleep: bool) -> None:
        """Teleport robot ``robot`` (``OdeWorld.place_robot``): its bodies to ``positions``
        ``(n, 3)`` m with ``rotations`` ``(n, 3, 3)``, at rest, disabled if ``asleep``; every
        hinge's target velocity 0."""
        fns, nb, bodies, nj, joints = self._place_args[robot]
        pos = np.ascontiguousarray(positions, dtype=float)
        rot = np.ascontiguousarray(rotations, dtype=float)
        if pos.shape != (nb, 3) or rot.shape != (nb, 3, 3):
            raise ValueError(f"placement needs ({nb}, 3) positions and ({nb}, 3, 3) rotations")
        self._lib.ode_place(
            fns,
            nb,
            bodies,
            compiled.address(pos),
            compiled.address(rot),
            int(asleep),
            nj,
            joints,
            ode.PARAM_VEL,
        )

    def frp(self, m: int) -> None:
        """Sum the ``m`` sensed contacts' feedback per force sensor into the world's sums
        array (``OdeWorld._read_feedback``)."""
        fb, pair, pos, side, n, sums = self._frp_args
        self._lib.ode_frp(m, fb, pair, pos, side, n, sums)

    def drag(self) -> int:
        """Drag on every body (``OdeWorld._apply_drag``); returns the index of a body whose
        velocity is not sane (then no force was added), else -1."""
        return self._lib.ode_drag(*self._drag_args)

    def realise(self, robot: int, targets: np.ndarray) -> None:
        """Robot ``robot``'s due targets, rad/s, NaN = none (``OdeWorld._realise``)."""
        fns, n, joints, child, limits, vmax = self._realise_args[robot]
        targets = np.ascontiguousarray(targets, dtype=float)
        self._lib.ode_realise(
            fns, n, joints, child, compiled.address(targets), limits, vmax, ode.PARAM_VEL
        )

    def collide(self, stamp: int) -> int:
        """Contact joints for this step; returns how many sensed contacts it wrote to the
        world's pair and position arrays, and marks the pairs that touched with ``stamp``
        (``OdeWorld._collide`` does the same in Python)."""
        return self._lib.ode_collide(*self._collide_args, stamp)
