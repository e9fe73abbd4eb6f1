/* The Python-side loops of robocup_gym.sim.engines.ode.world.OdeWorld in C: drag on every body,
 * the hinge effector's rules for a command, contact generation, reading the state (with its
 * sanity check), summing the foot sensors' contact forces, saving and restoring the bodies, and
 * a placement's ODE calls. In Python they make ~200 ctypes calls a cycle, as long as ODE's own
 * dWorldStep.
 *
 * ODE is called through the function pointers Python's ctypes binding already holds
 * (robocup_gym/sim/engines/ode/lib.py), so this file needs neither ODE's headers nor linking. The
 * structs mirror the ctypes ones in lib.py (ODE 0.16, double precision). Every call is made
 * with the same arguments in the same order as the Python it replaces, so the results are
 * bit-equal (tests/sim/test_ode_reference.py). Compiled by robocup_gym/sim/compiled.py.
 */
#include <math.h>

typedef double dReal;
typedef void* dID;

typedef struct {
  int mode;
  dReal mu, mu2, rho, rho2, rhoN, bounce, bounce_vel, soft_erp, soft_cfm;
  dReal motion1, motion2, motionN, slip1, slip2;
} dSurfaceParameters;

typedef struct {
  dReal pos[4];
  dReal normal[4];
  dReal depth;
  dID g1, g2;
  int side1, side2;
} dContactGeom;

typedef struct {
  dSurfaceParameters surface;
  dContactGeom geom;
  dReal fdir1[4];
} dContact;

typedef struct {
  dReal f1[4], t1[4], f2[4], t2[4];
} dJointFeedback;

typedef struct {
  int (*dCollide)(dID, dID, int, dContactGeom*, int);
  dID (*dJointCreateContact)(dID, dID, const dContact*);
  void (*dJointAttach)(dID, dID, dID);
  void (*dJointSetFeedback)(dID, dJointFeedback*);
  const dReal* (*dBodyGetLinearVel)(dID);
  const dReal* (*dBodyGetAngularVel)(dID);
  void (*dBodyAddForce)(dID, dReal, dReal, dReal);
  void (*dBodyAddTorque)(dID, dReal, dReal, dReal);
  dReal (*dJointGetHingeAngle)(dID);
  void (*dJointSetHingeParam)(dID, int, dReal);
  void (*dBodyEnable)(dID);
  void (*dGeomGetAABB)(dID, dReal*);
  const dReal* (*dBodyGetPosition)(dID);
  const dReal* (*dBodyGetRotation)(dID);
  dReal (*dJointGetHingeAngleRate)(dID);
  const dReal* (*dBodyGetQuaternion)(dID);
  int (*dBodyIsEnabled)(dID);
  void (*dBodySetPosition)(dID, dReal, dReal, dReal);
  void (*dBodySetQuaternion)(dID, const dReal*);
  void (*dBodySetLinearVel)(dID, dReal, dReal, dReal);
  void (*dBodySetAngularVel)(dID, dReal, dReal, dReal);
  void (*dBodyDisable)(dID);
  void (*dBodySetRotation)(dID, const dReal*);
} ode_fns;

int ode_sizeof_contact(void) { return (int)sizeof(dContact); }

/* Drag F = -lin v, torque -ang w on each body; coef holds (lin, ang) per body. First every
 * body's velocities are checked: if one is not finite or beyond `limit` (the solver blew up;
 * ODE's next step would abort the process in its quaternion normalisation), nothing is done and
 * the body's index is returned; else -1. */
int ode_drag(const ode_fns* f, int n, dID* bodies, const double* coef, double limit) {
  for (int i = 0; i < n; i++) {
    const dReal* v = f->dBodyGetLinearVel(bodies[i]);
    const dReal* w = f->dBodyGetAngularVel(bodies[i]);
    for (int j = 0; j < 3; j++)
      if (!(fabs(v[j]) < limit && fabs(w[j]) < limit)) return i;  /* NaN fails too */
  }
  for (int i = 0; i < n; i++) {
    dID b = bodies[i];
    const dReal* v = f->dBodyGetLinearVel(b);
    const dReal* w = f->dBodyGetAngularVel(b);
    double lin = coef[2 * i], ang = coef[2 * i + 1];
    f->dBodyAddForce(b, -lin * v[0], -lin * v[1], -lin * v[2]);
    f->dBodyAddTorque(b, -ang * w[0], -ang * w[1], -ang * w[2]);
  }
  return -1;
}

/* SimSpark's hinge effector for one robot's targets (rad/s, NaN = no command): a joint not
 * strictly inside its limits keeps its target; the target is clipped to the joint's max speed;
 * a non-zero one wakes the joint's child body. */
void ode_realise(const ode_fns* f, int n, dID* joints, dID* child, const double* targets,
                 const double* limits, const double* vmax, int param_vel) {
  for (int k = 0; k < n; k++) {
    double v = targets[k];
    if (isnan(v)) continue;
    double angle = f->dJointGetHingeAngle(joints[k]);
    if (!(limits[2 * k] < angle && angle < limits[2 * k + 1])) continue;
    v = v >= -vmax[k] ? v : -vmax[k];
    v = v <= vmax[k] ? v : vmax[k];
    f->dJointSetHingeParam(joints[k], param_vel, v);
    if (v != 0.0) f->dBodyEnable(child[k]);
  }
}

/* Whether two axis-aligned boxes (minx, maxx, miny, maxy, minz, maxz) are apart: then their
 * geoms cannot touch and dCollide would return no contact (world.py's _apart is the same). */
static int apart(const double* a, const double* b) {
  return a[1] < b[0] || b[1] < a[0] || a[3] < b[2] || b[3] < a[2] || a[5] < b[4] || b[5] < a[4];
}

/* Contact joints for every pair (g1, g2, body1, body2 in pairs[4p..4p+3], the mixed surface in
 * surfaces[p]); contacts of pairs with sensed[p] get a feedback slot, and their pair index and
 * position are written out. Returns the number of sensed contacts. A pair whose geoms both have
 * an AABB slot (slots[2p], slots[2p+1] >= 0; not the ground plane) and whose boxes are apart is
 * skipped, exactly as dCollide would skip it, but without its cost: with many robots most pairs
 * are far apart. aabb holds 6 numbers per slot geom (slot_geoms), filled here. Every pair that
 * made a contact gets hit[p] = stamp (the caller's cycle number), so the caller can tell which
 * pairs touched in this step without anything being cleared first. */
int ode_collide(const ode_fns* f, dID world, dID group, int npairs, dID* pairs,
                const dSurfaceParameters* surfaces, const int* sensed, int max_contacts,
                dContactGeom* buf, dJointFeedback* feedback, int* out_pair, double* out_pos,
                int nslots, dID* slot_geoms, const int* slots, double* aabb, int* hit,
                int stamp) {
  dContact contact;
  for (int j = 0; j < 4; j++) contact.fdir1[j] = 0.0;
  for (int k = 0; k < nslots; k++) f->dGeomGetAABB(slot_geoms[k], aabb + 6 * k);
  int m = 0;
  for (int p = 0; p < npairs; p++) {
    int s1 = slots[2 * p], s2 = slots[2 * p + 1];
    if (s1 >= 0 && s2 >= 0 && apart(aabb + 6 * s1, aabb + 6 * s2)) continue;
    int n = f->dCollide(pairs[4 * p], pairs[4 * p + 1], max_contacts, buf,
                        (int)sizeof(dContactGeom));
    if (!n) continue;
    hit[p] = stamp;
    contact.surface = surfaces[p];
    for (int k = 0; k < n; k++) {
      contact.geom = buf[k];
      dID joint = f->dJointCreateContact(world, group, &contact);
      f->dJointAttach(joint, pairs[4 * p + 2], pairs[4 * p + 3]);
      if (sensed[p]) {
        f->dJointSetFeedback(joint, feedback + m);
        out_pair[m] = p;
        for (int j = 0; j < 3; j++) out_pos[3 * m + j] = buf[k].pos[j];
        m++;
      }
    }
  }
  return m;
}

/* The state every perception reads, in one call: per body its position, rotation (3x3, row
 * major: ODE's 3x4 without the padding column), linear and angular velocity (18 numbers per
 * body, world frame), and every hinge's angle and rate. Returns the index of the first body
 * whose position is not finite or `bound` (m) or more from the origin in a coordinate (the
 * world's sanity check), else -1. */
int ode_read(const ode_fns* f, int nb, dID* bodies, double* out, int nj, dID* joints,
             double* angles, double* rates, double bound) {
  int bad = -1;
  for (int i = 0; i < nb; i++) {
    double* o = out + 18 * i;
    const dReal* p = f->dBodyGetPosition(bodies[i]);
    const dReal* r = f->dBodyGetRotation(bodies[i]);
    const dReal* v = f->dBodyGetLinearVel(bodies[i]);
    const dReal* w = f->dBodyGetAngularVel(bodies[i]);
    for (int j = 0; j < 3; j++) {
      o[j] = p[j];
      o[3 + j] = r[j];
      o[6 + j] = r[4 + j];
      o[9 + j] = r[8 + j];
      o[12 + j] = v[j];
      o[15 + j] = w[j];
      if (bad < 0 && !(fabs(p[j]) < bound)) bad = i;  /* NaN fails too */
    }
  }
  for (int k = 0; k < nj; k++) {
    angles[k] = f->dJointGetHingeAngle(joints[k]);
    rates[k] = f->dJointGetHingeAngleRate(joints[k]);
  }
  return bad;
}

/* SimSpark's force resistance perceptors from the step's contact feedback, summed per sensor:
 * contact k (of m) has feedback slot k, pair out_pair[k] and position out_pos[3k..3k+2]; the
 * sensor of the pair's first body is side_slot[2p], of its second side_slot[2p+1] (-1: none).
 * Per sensor s, sums[8s..8s+7] = total force (3), sum of |force| * position (3), sum of
 * |force|, and the number of its contacts. The same additions in the same order as world.py's
 * Python loop (bit-equal). */
void ode_frp(int m, const dJointFeedback* fb, const int* out_pair, const double* out_pos,
             const int* side_slot, int nslots, double* sums) {
  for (int s = 0; s < 8 * nslots; s++) sums[s] = 0.0;
  for (int k = 0; k < m; k++) {
    int p = out_pair[k];
    for (int side = 0; side < 2; side++) {
      int s = side_slot[2 * p + side];
      if (s < 0) continue;
      const dReal* f = side ? fb[k].f2 : fb[k].f1;
      double fx = f[0], fy = f[1], fz = f[2];
      double* a = sums + 8 * s;
      double magnitude = sqrt(fx * fx + fy * fy + fz * fz);
      a[0] += fx;
      a[1] += fy;
      a[2] += fz;
      a[3] += magnitude * out_pos[3 * k];
      a[4] += magnitude * out_pos[3 * k + 1];
      a[5] += magnitude * out_pos[3 * k + 2];
      a[6] += magnitude;
      a[7] += 1.0;
    }
  }
}

/* Save (save != 0) or restore the bodies' complete dynamic state: per body its position (3),
 * quaternion (4), linear and angular velocity (3 + 3) and whether it is enabled (1): 14 numbers
 * in out[14i..]. Restoring makes the same ODE calls as world.py's Python loop (bit-equal). */
void ode_bodies(const ode_fns* f, int nb, dID* bodies, double* out, int save) {
  for (int i = 0; i < nb; i++) {
    dID b = bodies[i];
    double* o = out + 14 * i;
    if (save) {
      const dReal* p = f->dBodyGetPosition(b);
      const dReal* q = f->dBodyGetQuaternion(b);
      const dReal* v = f->dBodyGetLinearVel(b);
      const dReal* w = f->dBodyGetAngularVel(b);
      for (int j = 0; j < 3; j++) {
        o[j] = p[j];
        o[7 + j] = v[j];
        o[10 + j] = w[j];
      }
      for (int j = 0; j < 4; j++) o[3 + j] = q[j];
      o[13] = f->dBodyIsEnabled(b);
    } else {
      f->dBodySetPosition(b, o[0], o[1], o[2]);
      f->dBodySetQuaternion(b, o + 3);
      f->dBodySetLinearVel(b, o[7], o[8], o[9]);
      f->dBodySetAngularVel(b, o[10], o[11], o[12]);
      if (o[13] != 0.0)
        f->dBodyEnable(b);
      else
        f->dBodyDisable(b);
    }
  }
}

/* Teleport one robot (OdeWorld.place_robot): body i to position pos[3i..3i+2] with rotation
 * rot[9i..9i+8] (3x3, row major), at rest, enabled unless `asleep`; every hinge's target
 * velocity (parameter param_vel) to 0. The same ODE calls in the same order as the Python
 * loop. */
void ode_place(const ode_fns* f, int nb, dID* bodies, const double* pos, const double* rot,
               int asleep, int nj, dID* joints, int param_vel) {
  for (int i = 0; i < nb; i++) {
    dID b = bodies[i];
    const double* r = rot + 9 * i;
    dReal m[12] = {r[0], r[1], r[2], 0.0, r[3], r[4], r[5], 0.0, r[6], r[7], r[8], 0.0};
    f->dBodySetPosition(b, pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]);
    f->dBodySetRotation(b, m);
    f->dBodySetLinearVel(b, 0.0, 0.0, 0.0);
    f->dBodySetAngularVel(b, 0.0, 0.0, 0.0);
    if (asleep)
      f->dBodyDisable(b);
    else
      f->dBodyEnable(b);
  }
  for (int k = 0; k < nj; k++) f->dJointSetHingeParam(joints[k], param_vel, 0.0);
}
