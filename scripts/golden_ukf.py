#!/usr/bin/env python3
"""Independent numpy UKF on the imu-fdi vehicle model: writes the golden CSVs
that `tests/golden_ukf.rs` compares the Rust `f64` filter against.

Written from SPEC.md §3–4, not from the Rust code:
  * model: body velocity + ZYX Euler kinematics, explicit midpoint (RK2) step,
    roll and yaw wrapped to (-pi, pi];
  * process noise: Q = M1 dt + M2 dt^2/2 with M1 = G q G^T, M2 = A M1 + (A M1)^T,
    A and G the analytic Jacobians (checked here against finite differences);
  * UKF: scaled sigma points (alpha=1, beta=2, kappa=0), sigma points redrawn
    from the predicted mean and covariance for the update, circular means
    (weighted mean of wrapped differences to the first sigma point), wrapped
    residuals, only the available measurement rows fused (Kalman update on
    the selected sub-vector).

Usage: python3 scripts/golden_ukf.py  (writes tests/data/golden_ukf_m1.csv, _m2.csv)
"""
import os
import numpy as np

G = 9.80665
HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "..", "tests", "data")


def wrap(a):
    w = np.mod(a + np.pi, 2 * np.pi) - np.pi
    return np.where(w <= -np.pi, w + 2 * np.pi, w)


def f(x, u):
    U, V, W, phi, th, psi = x
    ax, ay, az, p, q, r = u
    sp, cp, st, ct = np.sin(phi), np.cos(phi), np.sin(th), np.cos(th)
    return np.array([
        V * r - W * q - G * st + ax,
        -U * r + W * p + G * ct * sp + ay,
        U * q - V * p + G * ct * cp + az,
        p + (q * sp + r * cp) * st / ct,
        q * cp - r * sp,
        (q * sp + r * cp) / ct,
    ])


def step(x, u, dt):
    k1 = f(x, u)
    k2 = f(x + 0.5 * dt * k1, u)
    y = x + dt * k2
    y[3] = wrap(y[3])
    y[5] = wrap(y[5])
    return y


def jac(fun, x, eps=1e-6):
    n = len(x)
    J = np.zeros((len(fun(x)), n))
    for k in range(n):
        e = np.zeros(n); e[k] = eps
        J[:, k] = (fun(x + e) - fun(x - e)) / (2 * eps)
    return J


def A_analytic(x, u):
    U, V, W, phi, th, psi = x
    p, q, r = u[3:]
    sp, cp, st, ct = np.sin(phi), np.cos(phi), np.sin(th), np.cos(th)
    a = q * sp + r * cp
    b = q * cp - r * sp
    return np.array([
        [0, r, -q, 0, -G * ct, 0],
        [-r, 0, p, G * ct * cp, -G * st * sp, 0],
        [q, -p, 0, -G * ct * sp, -G * st * cp, 0],
        [0, 0, 0, b * st / ct, a / ct**2, 0],
        [0, 0, 0, -a, 0, 0],
        [0, 0, 0, b / ct, a * st / ct**2, 0],
    ])


def B_analytic(x):
    U, V, W, phi, th, psi = x
    sp, cp, st, ct = np.sin(phi), np.cos(phi), np.sin(th), np.cos(th)
    return np.array([
        [1, 0, 0, 0, -W, V],
        [0, 1, 0, W, 0, -U],
        [0, 0, 1, -V, U, 0],
        [0, 0, 0, 1, sp * st / ct, cp * st / ct],
        [0, 0, 0, 0, cp, -sp],
        [0, 0, 0, 0, sp / ct, cp / ct],
    ])


def Qd(x, u, psd, dt):
    A, B = A_analytic(x, u), B_analytic(x)
    M1 = B @ np.diag(psd) @ B.T
    M2 = A @ M1 + (A @ M1).T
    Q = M1 * dt + M2 * dt * dt / 2
    return 0.5 * (Q + Q.T)


def rot_nb(phi, th, psi):
    cp, sp, ct, st, cy, sy = np.cos(phi), np.sin(phi), np.cos(th), np.sin(th), np.cos(psi), np.sin(psi)
    return np.array([
        [ct * cy, sp * st * cy - cp * sy, cp * st * cy + sp * sy],
        [ct * sy, sp * st * sy + cp * cy, cp * st * sy - sp * cy],
        [-st, sp * ct, cp * ct],
    ])


def h(x, model):
    v = x[:3] if model == "m1" else rot_nb(x[3], x[4], x[5]) @ x[:3]
    return np.concatenate([v, x[3:]])


ANG_X = np.array([False, False, False, True, True, True])
ANG_Z = ANG_X.copy()


def diffv(a, b, ang):
    d = a - b
    d[ang] = wrap(d[ang])
    return d


class UKF:
    def __init__(self, x, P, alpha=1.0, beta=2.0, kappa=0.0):
        n = len(x)
        lam = alpha**2 * (n + kappa) - n
        self.c = n + lam
        self.wm = np.full(2 * n + 1, 1 / (2 * self.c))
        self.wc = self.wm.copy()
        self.wm[0] = lam / self.c
        self.wc[0] = lam / self.c + 1 - alpha**2 + beta
        self.x, self.P = x.copy(), P.copy()

    def points(self):
        L = np.linalg.cholesky(self.P)
        s = np.sqrt(self.c) * L
        return np.vstack([self.x, self.x + s.T, self.x - s.T])

    def mean(self, Y, ang):
        ref = Y[0]
        m = ref + sum(w * diffv(y, ref, ang) for w, y in zip(self.wm, Y))
        m[ang] = wrap(m[ang])
        return m

    def predict(self, fx, Q):
        Y = np.array([fx(c) for c in self.points()])
        m = self.mean(Y, ANG_X)
        P = Q.copy()
        for w, y in zip(self.wc, Y):
            d = diffv(y, m, ANG_X)
            P += w * np.outer(d, d)
        self.x, self.P = m, 0.5 * (P + P.T)

    def update(self, z, avail, hx, R):
        X = self.points()
        Z = np.array([hx(c) for c in X])
        zm = self.mean(Z, ANG_Z)
        idx = np.flatnonzero(avail)
        Pzz = np.diag(R)[np.ix_(idx, idx)].copy()
        Pxz = np.zeros((6, len(idx)))
        for w, zp, xp in zip(self.wc, Z, X):
            dz = diffv(zp, zm, ANG_Z)[idx]
            dx = diffv(xp, self.x, ANG_X)
            Pzz += w * np.outer(dz, dz)
            Pxz += w * np.outer(dx, dz)
        K = np.linalg.solve(Pzz.T, Pxz.T).T
        nu = diffv(z, zm, ANG_Z)[idx]
        x = self.x + K @ nu
        x[ANG_X] = wrap(x[ANG_X])
        P = self.P - K @ Pzz @ K.T
        self.x, self.P = x, 0.5 * (P + P.T)


def run(model, steps, seed):
    rng = np.random.default_rng(seed)
    dt = 0.01
    psd = np.array([6e-5] * 3 + [2e-7] * 3) if model == "m1" else np.array([1e-3] * 3 + [4e-6] * 3)
    sig = np.array([0.01] * 3 + list(np.radians([0.02, 0.02, 0.05]))) if model == "m1" else np.array([0.05] * 3 + list(np.radians([0.1, 0.1, 0.2])))
    R = sig**2
    speed = 2.0 if model == "m1" else 20.0
    x0 = np.array([speed, 0.05, -0.02, 0.03, -0.05, 3.0])
    P0 = np.diag(np.array([0.1, 0.1, 0.1] + list(np.radians([1.0, 1.0, 2.0])))**2)
    x_init = x0 + rng.normal(0, np.sqrt(np.diag(P0)))
    ukf = UKF(x_init, P0)
    truth = x0.copy()
    rows = []
    for k in range(steps):
        t = k * dt
        # A manoeuvring input: yaw turn through ±pi (wrap), roll and pitch sweeps.
        u_true = np.array([
            0.3 * np.sin(0.5 * t), 0.2 * np.cos(0.7 * t), -G * 0.98,
            0.3 * np.sin(1.1 * t), 0.2 * np.cos(0.9 * t), 0.8 + 0.3 * np.sin(0.3 * t),
        ])
        truth = step(truth, u_true, dt)
        u_meas = u_true + rng.normal(0, [0.02, 0.02, 0.02, 0.002, 0.002, 0.002])
        x_prior = ukf.x.copy()
        ukf.predict(lambda s: step(s, u_meas, dt), Qd(x_prior, u_meas, psd, dt))
        avail = np.zeros(6, dtype=bool)
        if k % 5 == 4:
            avail[3:] = True
        if k % 10 == 9:
            avail[:3] = True
        if k % 50 == 49:
            avail[1] = False  # a subset: one velocity channel missing
        z = h(truth, model) + rng.normal(0, sig)
        z[3:] = wrap(z[3:])
        if avail.any():
            ukf.update(z, avail, lambda s: h(s, model), R)
        row = [t, dt, *u_meas, *np.where(avail, z, np.nan), *avail.astype(int), *ukf.x]
        iu = np.triu_indices(6)
        row += list(ukf.P[iu])
        rows.append(row)
    return rows, psd, sig, x_init, np.sqrt(np.diag(P0))


def main():
    # Self-check of the analytic Jacobians.
    x = np.array([2.0, 0.3, -0.2, 0.4, -0.3, 2.5]); u = np.array([0.5, -0.2, -9.5, 0.1, -0.2, 0.3])
    assert np.abs(A_analytic(x, u) - jac(lambda s: f(s, u), x)).max() < 1e-7
    assert np.abs(B_analytic(x) - jac(lambda v: f(x, v), u)).max() < 1e-7
    os.makedirs(OUT, exist_ok=True)
    for model, seed in (("m1", 11), ("m2", 12)):
        rows, psd, sig, x_init, s0 = run(model, 1200, seed)
        hdr = ["t", "dt"] + [f"u{i}" for i in range(6)] + [f"z{i}" for i in range(6)] + [f"avail{i}" for i in range(6)] \
            + [f"x{i}" for i in range(6)] + [f"p{i}{j}" for i in range(6) for j in range(i, 6)]
        path = os.path.join(OUT, f"golden_ukf_{model}.csv")
        with open(path, "w") as fh:
            fh.write("# " + " ".join(repr(float(v)) for v in np.concatenate([psd, sig, x_init, s0])) + "\n")
            fh.write(",".join(hdr) + "\n")
            for r in rows:
                fh.write(",".join("" if (isinstance(v, float) and np.isnan(v)) else repr(float(v)) for v in r) + "\n")
        print("wrote", path, len(rows), "rows")


if __name__ == "__main__":
    main()
