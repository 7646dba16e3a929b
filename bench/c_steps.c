/* The compiled steps of mechviz written in C, to measure what "the same step costs in C".
 *
 * The RK4 kernels (rk4_cyclotron, rk4_hoop, rk4_free_body) are generated from the equations
 * written once, into c_rk4_generated.h (bench/c_form.py), from the benchmark problems' starts
 * and parameters; the symmetric methods' kernels (Boris, the free body's splitting) are the
 * methods' own maps, written here by hand as the product's are (dynamics/cyclotron.py,
 * disk.py). Scalar locals, the whole time loop inside one function, IEEE semantics (no
 * -ffast-math). The state lives in locals across steps, which is the fastest shape C allows;
 * numba's kernels store it back to the caller's array every step.
 *
 * Built and run by bench/experiments.py (the header written beside it first):
 *   gcc -O2 -I<folder of c_rk4_generated.h> c_steps.c -lm ; ./a.out N REPEATS
 * Prints one line per kernel: name, median ns/step, and a checksum of the final state.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "c_rk4_generated.h"

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
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
    kernel ks[] = {rk4_cyclotron, boris, rk4_hoop, rk4_free_body, splitting};
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
