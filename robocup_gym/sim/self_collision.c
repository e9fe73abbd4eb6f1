/* rcssserver3d's self-collision test (robocup_gym/sim/self_collision.py, `colliding`) in C:
 * the same arithmetic in the same order as the NumPy reference, for every pair of boxes. */
#include <math.h>

/* pos: (n, 3); rot: (n, 3, 3) row-major, columns = box axes; half: (n, 3);
 * pairs: (p, 2) int32; out: (p,) uint8 (1 = collides). Returns the number that collide. */
int rg_self_collisions(int p, const double* pos, const double* rot, const double* half,
                       const int* pairs, double tol, unsigned char* out) {
  int hits = 0;
  for (int k = 0; k < p; k++) {
    const int a = pairs[2 * k], b = pairs[2 * k + 1];
    const double* ra = rot + 9 * a;
    const double* rb = rot + 9 * b;
    const double* ha = half + 3 * a;
    const double* hb = half + 3 * b;
    double rel[3], c[3][3], ac[3][3], t[3], u[3];
    for (int i = 0; i < 3; i++) rel[i] = pos[3 * b + i] - pos[3 * a + i];
    for (int i = 0; i < 3; i++)
      for (int j = 0; j < 3; j++) {
        /* C[i][j] = A_i . B_j, A_i = column i of ra */
        double s = ra[0 * 3 + i] * rb[0 * 3 + j];
        s += ra[1 * 3 + i] * rb[1 * 3 + j];
        s += ra[2 * 3 + i] * rb[2 * 3 + j];
        c[i][j] = s;
        ac[i][j] = fabs(s);
      }
    for (int i = 0; i < 3; i++) {
      double s = ra[0 * 3 + i] * rel[0];
      s += ra[1 * 3 + i] * rel[1];
      s += ra[2 * 3 + i] * rel[2];
      t[i] = s;
      s = rb[0 * 3 + i] * rel[0];
      s += rb[1 * 3 + i] * rel[1];
      s += rb[2 * 3 + i] * rel[2];
      u[i] = s;
    }
    int sep = 0;
    for (int i = 0; i < 3 && !sep; i++) {
      double e = ac[i][0] * hb[0];
      e += ac[i][1] * hb[1];
      e += ac[i][2] * hb[2];
      sep = fabs(t[i]) + tol > ha[i] + e;
    }
    for (int j = 0; j < 3 && !sep; j++) {
      double e = ac[0][j] * ha[0];
      e += ac[1][j] * ha[1];
      e += ac[2][j] * ha[2];
      sep = fabs(u[j]) + tol > hb[j] + e;
    }
    for (int i = 0; i < 3 && !sep; i++) {
      const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
      for (int j = 0; j < 3 && !sep; j++) {
        const int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
        double dist = fabs(t[i2] * c[i1][j] - t[i1] * c[i2][j]);
        double ext = ha[i1] * ac[i2][j] + ha[i2] * ac[i1][j];
        ext = ext + (hb[j1] * ac[i][j2] + hb[j2] * ac[i][j1]);
        sep = dist + tol > ext;
      }
    }
    out[k] = (unsigned char)!sep;
    hits += !sep;
  }
  return hits;
}
