/* The per-cycle work of robocup_gym.sim.engines.mujoco.world.World.step in C (compiled on first use by
 * robocup_gym/sim/compiled.py against the installed MuJoCo's headers; no MuJoCo function is
 * called, only mjModel/mjData fields are read and written).
 *
 * It does exactly what the NumPy path of World.step does (World._step_numpy and the methods it
 * calls), operation for operation in the same floating-point order, so that both give bit-equal
 * states; tests/sim/test_compiled.py checks this. Read the Python for the why of each rule
 * (ODE's velocity motor, stops, surface layer, creep compensation); this file only repeats the
 * arithmetic. Compile without -ffast-math and with -ffp-contract=off (no fused multiply-add).
 *
 * Units: angles rad, velocities rad/s or m/s, times s, torques N·m.
 */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include <mujoco/mjdata.h>
#include <mujoco/mjmodel.h>
#include <mujoco/mujoco.h>

typedef struct {
  /* sizes */
  int32_t n;        /* motor joints of all robots, canonical order (robot after robot) */
  int32_t nrobots;
  int32_t ndrag;    /* robot bodies with drag; their drag sensors open sensordata (6 each) */
  int32_t ball_qpos, ball_qvel, ball_pair;
  /* per joint, canonical order */
  const int32_t* qpos_j;
  const int32_t* qvel_j;
  const double* lo;
  const double* hi;
  const double* vmax;
  double* targets;        /* active motor targets (world state) */
  double* q_ref;          /* creep compensation reference (world state) */
  uint8_t* motor_lost;    /* world state */
  double* cmd;            /* due commands, NaN = none; consumed (set to NaN) by rg_pre */
  uint8_t* at_lo;         /* scratch */
  uint8_t* at_hi;
  uint8_t* limited;
  uint8_t* away;
  double* q;
  double* mt;
  /* per joint, dof order */
  const int32_t* sort;    /* dof-order position k -> canonical index */
  const int32_t* dofs;    /* dof-order position k -> dof address */
  const double* motor_b;
  double* shift;          /* the motor rows' reference shift, compacted to the rows present */
  uint8_t* rows;          /* scratch: row present */
  /* per robot */
  const int32_t* qvel_root;
  const int32_t* torso_body;
  double* prev_vel;       /* nrobots x 3 */
  double* accel;          /* nrobots x 3 */
  /* per drag body */
  const int32_t* drag_body;
  /* ball-ground contact reference, [bouncy][2] */
  double ball_solref[4];
  /* flags shared with Python: relaxed, bouncy, any_limited, any_away, nrows */
  int32_t* flags;
  /* constants */
  double cycle, inv_cycle, inv_timestep, creep_window;
  double stop_erp, stop_bounce, fudge_torque, max_torque, saturated;
  double surface_layer, gravity, drag_lin, drag_ang;
  double ball_radius, ground_z, bounce_min_speed, diverged_qvel_sq;
} rg_world;

enum { F_RELAXED = 0, F_BOUNCY = 1, F_LIMITED = 2, F_AWAY = 3, F_NROWS = 4 };

int rg_header_version(void) { return mjVERSION_HEADER; }
int rg_sizeof_world(void) { return (int)sizeof(rg_world); }

static inline double clip(double x, double lo, double hi) {
  /* NumPy's clip: minimum(maximum(x, lo), hi) */
  double y = x > lo ? x : lo;
  return y < hi ? y : hi;
}

static inline double maximum(double a, double b) { return a >= b ? a : b; }

/* Before the cycle's physics: realise the due commands, the motors' targets with creep
 * compensation and ODE's stop rules, the motor rows' reference shift, warm start, and the
 * ball-ground contact mode (World._step_numpy up to the MuJoCo steps). */
void rg_pre(rg_world* w, mjModel* m, mjData* d) {
  const int n = w->n;
  const double* qpos = d->qpos;
  int any_limited = 0;
  for (int i = 0; i < n; i++) {
    double q = qpos[w->qpos_j[i]];
    w->q[i] = q;
    w->at_lo[i] = q <= w->lo[i];
    w->at_hi[i] = q >= w->hi[i];
    w->limited[i] = w->at_lo[i] | w->at_hi[i];
    any_limited |= w->limited[i];
  }
  /* commands are taken only by joints strictly inside their range, clipped to max speed */
  for (int i = 0; i < n; i++) {
    double v = w->cmd[i];
    if (v == v) {
      if (!w->limited[i]) w->targets[i] = clip(v, -w->vmax[i], w->vmax[i]);
      w->cmd[i] = NAN;
    }
  }
  int any_away = 0;
  if (any_limited) {
    for (int i = 0; i < n; i++) {
      w->away[i] = (w->at_lo[i] && w->targets[i] > 0.0) || (w->at_hi[i] && w->targets[i] < 0.0);
      any_away |= w->away[i];
    }
  }
  /* creep compensation */
  const double erp_speed = w->stop_erp * w->inv_timestep;
  for (int i = 0; i < n; i++) {
    double q = w->q[i];
    double ref = w->motor_lost[i] ? q : w->q_ref[i];
    ref = clip(ref, q - w->creep_window, q + w->creep_window);
    double t = ref - q;
    t *= w->inv_cycle;
    t += w->targets[i];
    w->q_ref[i] = ref + w->targets[i] * w->cycle;
    if (any_limited && w->limited[i]) {
      double v = d->qvel[w->qvel_j[i]];
      if (w->at_hi[i]) {
        double into = maximum(v, 0.0) * w->stop_bounce;
        t = -maximum((q - w->hi[i]) * erp_speed, into);
      } else {
        double into = maximum(-v, 0.0) * w->stop_bounce;
        t = maximum((w->lo[i] - q) * erp_speed, into);
      }
    }
    w->mt[i] = t;
  }
  /* dof order: the motor rows' shift (only rows present) and the warm start */
  int nrows = 0;
  for (int k = 0; k < n; k++) {
    int i = w->sort[k];
    int dof = w->dofs[k];
    double t = w->mt[i];
    int row = !(any_away && w->away[i]);
    w->rows[k] = (uint8_t)row;
    if (row) w->shift[nrows++] = w->motor_b[k] * t;
    d->qacc_warmstart[dof] = (t - d->qvel[dof]) * w->inv_timestep;
  }
  if (any_away) {
    for (int k = 0; k < n; k++) m->dof_frictionloss[w->dofs[k]] = w->rows[k] * w->max_torque;
    for (int i = 0; i < n; i++)
      d->qfrc_applied[w->qvel_j[i]] =
          (w->at_lo[i] ? w->fudge_torque : -w->fudge_torque) * (double)w->away[i];
    w->flags[F_RELAXED] = 1;
  } else if (w->flags[F_RELAXED]) {
    for (int k = 0; k < n; k++) m->dof_frictionloss[w->dofs[k]] = w->max_torque;
    for (int i = 0; i < n; i++) d->qfrc_applied[w->qvel_j[i]] = 0.0;
    w->flags[F_RELAXED] = 0;
  }
  w->flags[F_LIMITED] = any_limited;
  w->flags[F_AWAY] = any_away;
  w->flags[F_NROWS] = nrows;
  /* ball-ground contact: bouncy only for a fast approach that reaches the ground this cycle */
  double z = qpos[w->ball_qpos + 2];
  double vz = d->qvel[w->ball_qvel + 2];
  int bouncy = vz < -w->bounce_min_speed && z - w->ball_radius - w->ground_z + vz * w->cycle < 0.0;
  if (bouncy != w->flags[F_BOUNCY]) {
    m->pair_solref[mjNREF * w->ball_pair] = w->ball_solref[2 * bouncy];
    m->pair_solref[mjNREF * w->ball_pair + 1] = w->ball_solref[2 * bouncy + 1];
    w->flags[F_BOUNCY] = bouncy;
  }
}

/* Between mj_step1 and mj_step2: on the first substep the accelerometers and the drag; every
 * substep the motor rows' shift, ODE's surface layer on contacts and the elastic stops. */
void rg_mid(rg_world* w, const mjModel* m, mjData* d, int first) {
  (void)m;
  if (first) {
    for (int r = 0; r < w->nrobots; r++) {
      const double* v = d->qvel + w->qvel_root[r];
      const double* rot = d->xmat + 9 * w->torso_body[r];
      double* prev = w->prev_vel + 3 * r;
      double a[3];
      for (int j = 0; j < 3; j++) {
        a[j] = (v[j] - prev[j]) * w->inv_cycle;
      }
      a[2] += w->gravity;
      for (int j = 0; j < 3; j++) prev[j] = v[j];
      for (int j = 0; j < 3; j++)
        w->accel[3 * r + j] = a[0] * rot[j] + a[1] * rot[3 + j] + a[2] * rot[6 + j];
    }
    const double* vel = d->sensordata;
    for (int b = 0; b < w->ndrag; b++) {
      double* f = d->xfrc_applied + 6 * w->drag_body[b];
      for (int j = 0; j < 3; j++) f[j] = vel[6 * b + j] * -w->drag_lin;
      for (int j = 3; j < 6; j++) f[j] = vel[6 * b + j] * -w->drag_ang;
    }
  }
  int nrows = w->flags[F_NROWS];
  for (int k = 0; k < nrows; k++) d->efc_aref[k] += w->shift[k];
  if (d->ncon) {
    int start = d->ne + d->nf + d->nl;
    for (int c = 0; c < d->ncon; c++) {
      int row = start + 3 * c;
      double s = maximum(d->efc_pos[row], -w->surface_layer);
      s *= d->efc_KBIP[4 * row];
      s *= d->efc_KBIP[4 * row + 2];
      d->efc_aref[row] += s;
    }
  }
  if (d->nl) {
    int start = d->ne + d->nf;
    for (int row = start; row < start + d->nl; row++) {
      double v = d->efc_vel[row];
      double implied = d->efc_aref[row] / w->inv_timestep;
      implied += v;
      double bounce = v * -w->stop_bounce;
      bounce = maximum(bounce, implied);
      bounce -= implied;
      bounce *= w->inv_timestep;
      d->efc_aref[row] += bounce;
    }
  }
}

/* After mj_step2: which motors lost motion this step (saturated at FMax, absent at a stop or
 * at a stop at all). Returns 1 if the state diverged (NaN/inf or |qvel|^2 >= limit). */
int rg_post(rg_world* w, const mjModel* m, mjData* d) {
  const int n = w->n;
  int j = 0;
  for (int k = 0; k < n; k++) {
    int i = w->sort[k];
    int moving = 0;
    if (w->rows[k]) {
      moving = fabs(d->efc_force[j]) < w->saturated;
      j++;
    }
    w->motor_lost[i] = !moving || (w->flags[F_LIMITED] && w->limited[i]);
  }
  double sq = 0.0;
  for (int k = 0; k < m->nv; k++) sq += d->qvel[k] * d->qvel[k];
  return !(sq < w->diverged_qvel_sq);
}
