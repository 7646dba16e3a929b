/* The compiled steps of mechviz written in C, to measure what "the same step costs in C".
 *
 * Each kernel has the arithmetic of its numba counterpart (dynamics/cyclotron.py, hoop.py,
 * disk.py): scalar locals, the whole time loop inside one function, IEEE semantics (no
 * -ffast-math). The state lives in locals across steps, which is the fastest shape C allows;
 * numba's kernels store it back to the caller's array every step.
 *
 * Built and run by dynamics/bench/percost.py:  gcc -O2 c_steps.c -lm ; ./a.out N REPEATS
 * Prints one line per kernel: name, median ns/step, and a checksum of the final state.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static double rk4_charge(long n, double h) {
    double w = 1.0, x = 1, y = 0, z = 0, u = 0, v = 1, vz = 0.1;
    for (long k = 0; k < n; k++) {
        double a1u = w * v, a1v = -w * u;
        double u1 = u + 0.5 * h * a1u, v1 = v + 0.5 * h * a1v;
        double a2u = w * v1, a2v = -w * u1;
        double u2 = u + 0.5 * h * a2u, v2 = v + 0.5 * h * a2v;
        double a3u = w * v2, a3v = -w * u2;
        double u3 = u + h * a3u, v3 = v + h * a3v;
        double a4u = w * v3, a4v = -w * u3;
        double c = h / 6.0;
        x = x + c * (u + 2.0 * (u1 + u2) + u3);
        y = y + c * (v + 2.0 * (v1 + v2) + v3);
        z = z + h * vz;
        double nu = u + c * (a1u + 2.0 * (a2u + a3u) + a4u);
        v = v + c * (a1v + 2.0 * (a2v + a3v) + a4v);
        u = nu;
    }
    return x + y + z + u + v;
}

static double boris(long n, double h) {
    double w = 1.0, x = 1, y = 0, z = 0, vx = 0, vy = 1, vz = 0.1;
    double t = 0.5 * w * h, s = 2.0 * t / (1.0 + t * t), half = 0.5 * h;
    for (long k = 0; k < n; k++) {
        x += half * vx; y += half * vy; z += half * vz;
        double px = vx + vy * t, py = vy - vx * t;
        vx += py * s; vy -= px * s;
        x += half * vx; y += half * vy; z += half * vz;
    }
    return x + y + z + vx + vy;
}

static inline void hoop_acc(double th1, double th2, double w1, double w2, double M, double m,
                            double ga, double *o1, double *o2) {
    double s = sin(th1 - th2), c = cos(th1 - th2);
    double r1 = -m * s * w2 * w2 - (M + m) * ga * sin(th1);
    double r2 = s * w1 * w1 - ga * sin(th2);
    double m11 = 2.0 * M + m, det = m11 - m * c * c;
    *o1 = (r1 - m * c * r2) / det;
    *o2 = (m11 * r2 - c * r1) / det;
}

static double rk4_hoop(long n, double h) {
    double M = 1.0, m = 0.5, ga = 9.81, q1 = 0.5, q2 = -0.3, u1 = 0, u2 = 0;
    for (long k = 0; k < n; k++) {
        double a1, b1, a2, b2, a3, b3, a4, b4, hh = 0.5 * h;
        hoop_acc(q1, q2, u1, u2, M, m, ga, &a1, &b1);
        double u1b = u1 + hh * a1, u2b = u2 + hh * b1;
        hoop_acc(q1 + hh * u1, q2 + hh * u2, u1b, u2b, M, m, ga, &a2, &b2);
        double u1c = u1 + hh * a2, u2c = u2 + hh * b2;
        hoop_acc(q1 + hh * u1b, q2 + hh * u2b, u1c, u2c, M, m, ga, &a3, &b3);
        double u1d = u1 + h * a3, u2d = u2 + h * b3;
        hoop_acc(q1 + h * u1c, q2 + h * u2c, u1d, u2d, M, m, ga, &a4, &b4);
        double c = h / 6.0;
        q1 = q1 + c * (u1 + 2.0 * (u1b + u1c) + u1d);
        q2 = q2 + c * (u2 + 2.0 * (u2b + u2c) + u2d);
        u1 = u1 + c * (a1 + 2.0 * (a2 + a3) + a4);
        u2 = u2 + c * (b1 + 2.0 * (b2 + b3) + b4);
    }
    return q1 + q2 + u1 + u2;
}

#define RATES(o, w1, w2, w3, q0, q1, q2, q3)                 \
    o[0] = k1 * (w2) * (w3);                                 \
    o[1] = k2 * (w3) * (w1);                                 \
    o[2] = k3 * (w1) * (w2);                                 \
    o[3] = 0.5 * (-(q1) * (w1) - (q2) * (w2) - (q3) * (w3)); \
    o[4] = 0.5 * ((q0) * (w1) + (q2) * (w3) - (q3) * (w2));  \
    o[5] = 0.5 * ((q0) * (w2) + (q3) * (w1) - (q1) * (w3));  \
    o[6] = 0.5 * ((q0) * (w3) + (q1) * (w2) - (q2) * (w1));

static double rk4_free(long n, double h) {
    double i1 = 0.25, i2 = 29.0 / 36.0, i3 = 19.0 / 18.0;
    double a[7] = {0.01, 1.0, 0.01, 1.0, 0.0, 0.0, 0.0};
    for (long k = 0; k < n; k++) {
        double k1 = (i2 - i3) / i1, k2 = (i3 - i1) / i2, k3 = (i1 - i2) / i3, hh = 0.5 * h;
        double b[7], c[7], d[7], e[7], t[7];
        RATES(b, a[0], a[1], a[2], a[3], a[4], a[5], a[6]);
        for (int j = 0; j < 7; j++) t[j] = a[j] + hh * b[j];
        RATES(c, t[0], t[1], t[2], t[3], t[4], t[5], t[6]);
        for (int j = 0; j < 7; j++) t[j] = a[j] + hh * c[j];
        RATES(d, t[0], t[1], t[2], t[3], t[4], t[5], t[6]);
        for (int j = 0; j < 7; j++) t[j] = a[j] + h * d[j];
        RATES(e, t[0], t[1], t[2], t[3], t[4], t[5], t[6]);
        double cc = h / 6.0;
        for (int j = 0; j < 7; j++) a[j] = a[j] + cc * (b[j] + 2.0 * (c[j] + d[j]) + e[j]);
    }
    return a[0] + a[1] + a[2] + a[3] + a[4] + a[5] + a[6];
}

/* Exact flow of L_i^2 / 2 I_i, as mechviz.dynamics.disk._rotation (two libm calls). */
static inline void rotation(double angle, double lj, double lk, double ij, double ik,
                            double *wj, double *wk, double *q0, double *qi, double *qj,
                            double *qk) {
    double ch = cos(0.5 * angle), sh = sin(0.5 * angle);
    double c = (ch - sh) * (ch + sh), s = 2.0 * sh * ch;
    double a0 = *q0, ai = *qi, aj = *qj, ak = *qk;
    *wj = (c * lj + s * lk) / ij;
    *wk = (-s * lj + c * lk) / ik;
    *q0 = ch * a0 - sh * ai;
    *qi = ch * ai + sh * a0;
    *qj = ch * aj + sh * ak;
    *qk = ch * ak - sh * aj;
}

static double splitting(long n, double h) {
    double i1 = 0.25, i2 = 29.0 / 36.0, i3 = 19.0 / 18.0;
    double w1 = 0.01, w2 = 1.0, w3 = 0.01, q0 = 1.0, q1 = 0.0, q2 = 0.0, q3 = 0.0, hh = 0.5 * h;
    for (long k = 0; k < n; k++) {
        rotation(w1 * hh, i2 * w2, i3 * w3, i2, i3, &w2, &w3, &q0, &q1, &q2, &q3);
        rotation(w2 * hh, i3 * w3, i1 * w1, i3, i1, &w3, &w1, &q0, &q2, &q3, &q1);
        rotation(w3 * h, i1 * w1, i2 * w2, i1, i2, &w1, &w2, &q0, &q3, &q1, &q2);
        rotation(w2 * hh, i3 * w3, i1 * w1, i3, i1, &w3, &w1, &q0, &q2, &q3, &q1);
        rotation(w1 * hh, i2 * w2, i3 * w3, i2, i3, &w2, &w3, &q0, &q1, &q2, &q3);
    }
    return w1 + w2 + w3 + q0 + q1 + q2 + q3;
}

typedef double (*kernel)(long, double);

static int cmp(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(int argc, char **argv) {
    long n = argc > 1 ? atol(argv[1]) : 1000000;
    int reps = argc > 2 ? atoi(argv[2]) : 5;
    const char *names[] = {"rk4-charge", "boris-charge", "rk4-hoop", "rk4-free-body", "splitting-free-body"};
    kernel ks[] = {rk4_charge, boris, rk4_hoop, rk4_free, splitting};
    double hs[] = {0.01, 0.01, 0.001, 0.001, 0.001};
    long scale[] = {1, 1, 8, 4, 8}; /* fewer steps for the expensive kernels */
    for (int i = 0; i < 5; i++) {
        long m = n / scale[i];
        double t[64], sum = ks[i](m / 10, hs[i]); /* untimed warm-up */
        if (reps > 64) reps = 64;
        for (int r = 0; r < reps; r++) {
            double t0 = now();
            sum += ks[i](m, hs[i]);
            t[r] = (now() - t0) / m * 1e9;
        }
        qsort(t, reps, sizeof(double), cmp);
        printf("%s %.3f %.17g\n", names[i], t[reps / 2], sum);
    }
    return 0;
}
