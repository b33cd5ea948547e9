/*
 * Goldfarb-Idnani dual active-set steps for min 0.5 |z - z_c|^2 (identity Hessian, i.e. the
 * whitened DMP fit), compiled so that one add/drop step costs O(n^2) flops and no interpreter
 * overhead. Called through ctypes from dmp/qp/dual_active_set.py, which owns every array.
 *
 * Storage: Q (n x n) and R (n x n, upper triangular in its first q columns) column-major,
 * Q[i + n*j]. The active normals N (n x q, GI convention n . z >= b) satisfy N = Q[:, :q] R[:q, :q].
 * The first neq active rows are equalities (free multipliers), the rest inequalities (u >= 0).
 *
 * Reference: D. Goldfarb, A. Idnani, Math. Programming 27 (1983) 1-33.
 */
/* Built against the stable ABI (dmp/qp/_build.py defines Py_LIMITED_API 3.11): the library uses no
   Python API beyond the empty module init at the end, so one build serves every CPython >= 3.11. */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

/* x86-64 builds carry an AVX2/FMA clone of the three GI entry points next to the baseline one, picked
   at load time (GCC function multiversioning through glibc ifuncs); the helpers below are inlined
   into each clone. */
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__GLIBC__)
#define GI_CLONES __attribute__((target_clones("avx2", "fma", "default")))
#else
#define GI_CLONES
#endif
#define GI_INLINE static inline __attribute__((always_inline))
/* the entry points ctypes looks up (exported on every platform, whatever the default visibility) */
#if defined(_WIN32)
#define GI_EXPORT __declspec(dllexport)
#else
#define GI_EXPORT __attribute__((visibility("default")))
#endif

#define GI_OK 0
#define GI_NEED_ROWS 0
#define GI_INFEASIBLE (-1)
#define GI_MAX_ITER (-2)

/* Four-wide vectors (GCC/Clang vector extensions: two SSE2 registers in the baseline build, one
   AVX register in the AVX2 clone) with two accumulators; no -ffast-math, which would break the
   INFINITY tests below. */
typedef double v4d __attribute__((vector_size(32)));

GI_INLINE v4d load4(const double *p) {
    v4d v;
    memcpy(&v, p, sizeof v);
    return v;
}

GI_INLINE double dot(int n, const double *a, const double *b) {
    v4d s0 = {0.0, 0.0, 0.0, 0.0}, s1 = {0.0, 0.0, 0.0, 0.0};
    int i = 0;
    for (; i + 8 <= n; i += 8) {
        s0 += load4(a + i) * load4(b + i);
        s1 += load4(a + i + 4) * load4(b + i + 4);
    }
    for (; i + 4 <= n; i += 4) s0 += load4(a + i) * load4(b + i);
    s0 += s1;
    double s = (s0[0] + s0[1]) + (s0[2] + s0[3]);
    for (; i < n; ++i) s += a[i] * b[i];
    return s;
}

GI_INLINE void directions(int n, int q, const double *Q, const double *R, const double *np_,
                          double *qt, double *d, double *r) {
    for (int j = 0; j < n; ++j) qt[j] = dot(n, Q + (size_t)n * j, np_);
    for (int i = 0; i < n; ++i) d[i] = 0.0;
    for (int j = q; j < n; ++j) {
        const double *col = Q + (size_t)n * j;
        const double a = qt[j];
        for (int i = 0; i < n; ++i) d[i] += col[i] * a;
    }
    /* back substitution R r = qt[:q], column by column (R is column-major: contiguous columns) */
    for (int i = 0; i < q; ++i) r[i] = qt[i];
    for (int i = q - 1; i >= 0; --i) {
        const double *col = R + (size_t)n * i;
        const double a = r[i] / col[i];
        r[i] = a;
        for (int k = 0; k < i; ++k) r[k] -= col[k] * a;
    }
}

GI_INLINE void rotate_cols(int n, double *Q, int a, int b, double c, double s) {
    double *qa = Q + (size_t)n * a, *qb = Q + (size_t)n * b;
    for (int i = 0; i < n; ++i) {
        const double x = qa[i], y = qb[i];
        qa[i] = c * x + s * y;
        qb[i] = -s * x + c * y;
    }
}

/* Append the normal whose Q^T n is qt as column q of R, rotating Q so R stays triangular. */
GI_INLINE void insert(int n, int *q, double *Q, double *R, double *qt) {
    for (int j = n - 1; j > *q; --j) {
        const double a = qt[j - 1], b = qt[j];
        if (b == 0.0) continue;
        const double h = sqrt(a * a + b * b); /* entries are O(1): no need for hypot's care */
        if (h == 0.0) continue;
        const double c = a / h, s = b / h;
        qt[j - 1] = h;
        qt[j] = 0.0;
        rotate_cols(n, Q, j - 1, j, c, s);
    }
    for (int i = 0; i <= *q; ++i) R[i + (size_t)n * (*q)] = qt[i];
    for (int i = *q + 1; i < n; ++i) R[i + (size_t)n * (*q)] = 0.0;
    *q += 1;
}

/* Remove active column k (0 <= k < q), restoring triangularity by rotations. */
GI_INLINE void delete_col(int n, int *q, double *Q, double *R, int k) {
    for (int j = k; j < *q - 1; ++j) memcpy(R + (size_t)n * j, R + (size_t)n * (j + 1), sizeof(double) * n);
    for (int j = k; j < *q - 1; ++j) {
        const double a = R[j + (size_t)n * j], b = R[j + 1 + (size_t)n * j];
        if (b == 0.0) continue;
        const double h = sqrt(a * a + b * b);
        if (h == 0.0) continue;
        const double c = a / h, s = b / h;
        for (int col = j; col < *q - 1; ++col) {
            const double x = R[j + (size_t)n * col], y = R[j + 1 + (size_t)n * col];
            R[j + (size_t)n * col] = c * x + s * y;
            R[j + 1 + (size_t)n * col] = -s * x + c * y;
        }
        R[j + 1 + (size_t)n * j] = 0.0;
        rotate_cols(n, Q, j, j + 1, c, s);
    }
    for (int i = 0; i < n; ++i) R[i + (size_t)n * (*q - 1)] = 0.0;
    *q -= 1;
}


/*
 * Take the equality e . z = f. Returns 0 when taken, 1 when dependent and consistent (skipped),
 * -1 when dependent and inconsistent. work: 3n doubles.
 */
GI_EXPORT GI_CLONES int gi_equality(int n, double *Q, double *R, double *u, int *q, double *z, const double *e, double f,
                double *work) {
    double *qt = work, *d = work + n, *r = work + 2 * n;
    directions(n, *q, Q, R, e, qt, d, r);
    const double s = dot(n, e, z) - f, dn = dot(n, d, e);
    if (dn <= 1e-12 * dot(n, e, e)) return fabs(s) > 1e-9 ? -1 : 1;
    const double t = -s / dn;
    for (int i = 0; i < n; ++i) z[i] += t * d[i];
    for (int i = 0; i < *q; ++i) u[i] -= t * r[i];
    u[*q] = t;
    insert(n, q, Q, R, qt);
    return 0;
}

/*
 * Add the most violated candidate row (G z <= h, row-major m x n) until none exceeds tol.
 * Returns GI_NEED_ROWS (0) when every candidate holds, GI_INFEASIBLE with the involved candidate
 * rows in info[0..*ninfo) and *eq_involved set, or GI_MAX_ITER. active[i] is the candidate index of
 * active inequality i (i < q - neq). work: 4n doubles.
 */
GI_EXPORT GI_CLONES int gi_solve(int n, int m, const double *G, const double *h, double *Q, double *R, double *u, int *active,
             int *q, int neq, double *z, double tol, int max_iter, int *iters, int *info, int *ninfo,
             int *eq_involved, double *work) {
    double *qt = work, *d = work + n, *r = work + 2 * n, *np_ = work + 3 * n;
    for (;;) {
        int p = -1;
        double worst = tol;
        for (int i = 0; i < m; ++i) {
            const double s = dot(n, G + (size_t)n * i, z) - h[i];
            if (s > worst) {
                worst = s;
                p = i;
            }
        }
        if (p < 0) return GI_NEED_ROWS;
        for (int i = 0; i < n; ++i) np_[i] = -G[(size_t)n * p + i];
        const double b_p = -h[p];
        double u_p = 0.0;
        for (;;) {
            if (*iters >= max_iter) return GI_MAX_ITER;
            *iters += 1;
            directions(n, *q, Q, R, np_, qt, d, r);
            const double s = dot(n, np_, z) - b_p;
            double t1 = INFINITY;
            int k = -1;
            for (int i = neq; i < *q; ++i) {
                if (r[i] > 1e-14) {
                    const double ratio = u[i] / r[i];
                    if (ratio < t1) {
                        t1 = ratio;
                        k = i;
                    }
                }
            }
            const double dn = dot(n, d, np_);
            const double t2 = dn <= 1e-12 * dot(n, np_, np_) ? INFINITY : -s / dn;
            if (!isfinite(t1) && !isfinite(t2)) {
                int c = 0;
                for (int i = neq; i < *q; ++i)
                    if (r[i] < -1e-14) info[c++] = active[i - neq];
                info[c++] = p;
                *ninfo = c;
                *eq_involved = 0;
                for (int i = 0; i < neq; ++i)
                    if (fabs(r[i]) > 1e-14) *eq_involved = 1;
                return GI_INFEASIBLE;
            }
            const double t = t1 < t2 ? t1 : t2;
            if (isfinite(t2))
                for (int i = 0; i < n; ++i) z[i] += t * d[i];
            for (int i = 0; i < *q; ++i) u[i] -= t * r[i];
            u_p += t;
            if (t2 <= t1) {
                u[*q] = u_p;
                active[*q - neq] = p;
                insert(n, q, Q, R, qt);
                break;
            }
            delete_col(n, q, Q, R, k); /* multiplier of active inequality k reached zero */
            for (int i = k; i < *q; ++i) u[i] = u[i + 1];
            for (int i = k - neq; i < *q - neq; ++i) active[i] = active[i + 1];
        }
    }
}

/*
 * Warm start from a primal guess: take the candidate rows rows[0..nrows) as active, each as an
 * equality (skipping rows dependent on those already taken), then drop the inequality with the
 * most negative multiplier and re-project z_c onto the remaining rows until every inequality
 * multiplier is >= 0. The result is what gi_solve requires (z optimal for its active rows, u >= 0),
 * reached in about one O(n^2) step per guessed row when the guess is nearly right (the active rows
 * of the previous linearisation). Returns the number of active inequalities. work: 4n doubles.
 */
GI_EXPORT GI_CLONES int gi_warm(int n, const double *G, const double *h, double *Q, double *R, double *u, int *active,
                      int *q, int neq, double *z, const double *zc, const int *rows, int nrows, double *work) {
    double *qt = work, *d = work + n, *r = work + 2 * n, *np_ = work + 3 * n;
    for (int a = 0; a < nrows && *q < n; ++a) {
        const int p = rows[a];
        for (int i = 0; i < n; ++i) np_[i] = -G[(size_t)n * p + i];
        directions(n, *q, Q, R, np_, qt, d, r);
        const double dn = dot(n, d, np_);
        /* nearly dependent (a normal within 1e-4 of the span taken): stays a mere candidate, since
           taking it as an equality would make R ill-conditioned; gi_solve's dual steps handle it */
        if (dn <= 1e-8 * dot(n, np_, np_)) continue;
        const double t = -(dot(n, np_, z) + h[p]) / dn; /* row p reads np_ . z >= -h[p] */
        for (int i = 0; i < n; ++i) z[i] += t * d[i];
        for (int i = 0; i < *q; ++i) u[i] -= t * r[i];
        u[*q] = t;
        active[*q - neq] = p;
        insert(n, q, Q, R, qt);
    }
    for (;;) {
        int k = -1;
        double most = 0.0;
        for (int i = neq; i < *q; ++i)
            if (u[i] < most) {
                most = u[i];
                k = i;
            }
        if (k < 0) return *q - neq;
        delete_col(n, q, Q, R, k);
        for (int i = k; i < *q; ++i) u[i] = u[i + 1];
        for (int i = k - neq; i < *q - neq; ++i) active[i] = active[i + 1];
        /* z still meets the remaining rows: their optimum is z_c + Q1 Q1^T (z - z_c), u = R^-1 Q1^T (z - z_c) */
        for (int i = 0; i < n; ++i) np_[i] = z[i] - zc[i];
        for (int j = 0; j < *q; ++j) qt[j] = dot(n, Q + (size_t)n * j, np_);
        for (int i = 0; i < n; ++i) z[i] = zc[i];
        for (int j = 0; j < *q; ++j) {
            const double *col = Q + (size_t)n * j;
            const double a = qt[j];
            for (int i = 0; i < n; ++i) z[i] += col[i] * a;
        }
        for (int i = 0; i < *q; ++i) u[i] = qt[i];
        for (int i = *q - 1; i >= 0; --i) {
            const double *col = R + (size_t)n * i;
            const double a = u[i] / col[i];
            u[i] = a;
            for (int j = 0; j < i; ++j) u[j] -= col[j] * a;
        }
    }
}

/*
 * Residuals of stacked constraint rows and their violated local maxima in time (the oracle's scan,
 * see dmp/qp/pool.py): series s at dense sample t reads
 *     r = nb[s, t] + sum_d apos[s, d, t] x[j, d]  (s < npos)  + sum_d avel[s - vfrom, d, t] v[j, d]  (s >= vfrom)
 * for the L level samples t = idx[j] with positions x and velocities v (L x n, row-major); arrays
 * nb (S x T), apos (npos x n x T), avel ((S - vfrom) x n x T) are C-ordered. Writes r to res
 * (S x L) when res is not NULL, and the series and sample of every r > thr that is >= both
 * neighbours (in level order) to out_s, out_t (up to cap). Returns the number of peaks (which may
 * exceed cap: the caller then asks again with room for all).
 */
GI_EXPORT int gi_scan(int S, int T, int L, const int64_t *idx, int n, int npos, int vfrom, const double *nb, const double *apos,
            const double *avel, const double *x, const double *v, double thr, double *res, int *out_s, int64_t *out_t,
            int cap, int64_t start, int64_t step, double *buf) {
    /* the level's samples are idx[j] = start + j step when step > 0 (a slice: strided reads the
       compiler can stream), otherwise the array idx; rows go to res (or the scratch buf, L doubles) */
    int count = 0;
    for (int s = 0; s < S; ++s) {
        double *r = res ? res + (size_t)s * L : buf;
        const double *nbs = nb + (size_t)s * T;
        if (step > 0) {
            for (int j = 0; j < L; ++j) r[j] = nbs[start + j * step];
        } else {
            for (int j = 0; j < L; ++j) r[j] = nbs[idx[j]];
        }
        for (int kind = 0; kind < 2; ++kind) {
            const int on = kind == 0 ? s < npos : s >= vfrom;
            if (!on) continue;
            const double *a = kind == 0 ? apos + (size_t)s * n * T : avel + (size_t)(s - vfrom) * n * T;
            const double *xv = kind == 0 ? x : v;
            for (int d = 0; d < n; ++d) {
                const double *ad = a + (size_t)d * T;
                if (step > 0) {
                    for (int j = 0; j < L; ++j) r[j] += ad[start + j * step] * xv[(size_t)j * n + d];
                } else {
                    for (int j = 0; j < L; ++j) r[j] += ad[idx[j]] * xv[(size_t)j * n + d];
                }
            }
        }
        for (int j = 0; j < L; ++j) {
            const double cur = r[j];
            if (cur > thr && (j == 0 || cur >= r[j - 1]) && (j + 1 == L || cur >= r[j + 1])) {
                if (count < cap) {
                    out_s[count] = s;
                    out_t[count] = step > 0 ? start + j * step : idx[j];
                }
                ++count;
            }
        }
    }
    return count;
}

/*
 * Rows G w <= h of the stacked constraint rows ids[0..m) (see gi_scan for the layout): row id reads
 * series s = series_of[id] at dense sample t = sample_of[id]; with cp = apos[s, :, t] (s < npos),
 * cv = avel[s - vfrom, :, t] (s >= vfrom), zero otherwise,
 *     G[i, b n + e] = Gx[t, b] (cp M)[e] + Gv[t, b] (cv M)[e],   h[i] = -nb[s, t] - cp . xf[t] - cv . vf[t]
 * (w = W.ravel() with W of shape (N, n), dmp/affine.py). Gx, Gv (T x N), xf, vf (T x n), M (n x n),
 * G (m x N n) row-major. work: 4n doubles.
 */
GI_EXPORT void gi_rows(int m, const int64_t *ids, const int64_t *series_of, const int64_t *sample_of, int T, int n, int N,
             int npos, int vfrom, const double *nb, const double *apos, const double *avel, const double *Gx,
             const double *Gv, const double *xf, const double *vf, const double *M, double *G, double *h,
             double *work) {
    double *cp = work, *cv = work + n, *cpm = work + 2 * n, *cvm = work + 3 * n;
    for (int i = 0; i < m; ++i) {
        const int64_t s = series_of[ids[i]], t = sample_of[ids[i]];
        double hi = -nb[s * T + t];
        for (int d = 0; d < n; ++d) {
            cp[d] = s < npos ? apos[(s * n + d) * T + t] : 0.0;
            cv[d] = s >= vfrom ? avel[((s - vfrom) * n + d) * T + t] : 0.0;
            hi -= cp[d] * xf[t * n + d] + cv[d] * vf[t * n + d];
        }
        for (int e = 0; e < n; ++e) {
            double a = 0.0, b = 0.0;
            for (int d = 0; d < n; ++d) {
                a += cp[d] * M[d * n + e];
                b += cv[d] * M[d * n + e];
            }
            cpm[e] = a;
            cvm[e] = b;
        }
        double *row = G + (size_t)i * N * n;
        const double *gx = Gx + (size_t)t * N, *gv = Gv + (size_t)t * N;
        for (int k = 0; k < N; ++k)
            for (int e = 0; e < n; ++e) row[k * n + e] = gx[k] * cpm[e] + gv[k] * cvm[e];
        h[i] = hi;
    }
}

/* The module only carries the C functions above (loaded with ctypes); it has no Python API. */
static struct PyModuleDef gi_module = {PyModuleDef_HEAD_INIT, "_gi_core", NULL, -1, NULL};

PyMODINIT_FUNC PyInit__gi_core(void) { return PyModule_Create(&gi_module); }
