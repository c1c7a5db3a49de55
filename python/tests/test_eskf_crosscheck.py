"""Independent cross-check of ftsmc-core's error-state Kalman filter.

An ESKF written here in numpy, in the matrix form of Sola 2017,
"Quaternion kinematics for the error-state Kalman filter"
(arXiv:1711.02508), is run on the readings of the fixture that
``crates/ftsmc-core/tests/eskf_fixture.rs`` writes, and its state,
covariance, innovations, NIS and gate decisions are compared with the Rust
filter's after every step (the Python filter runs on its own from the
initial state; it is never reset to the Rust values). Needs numpy and the
fixture only, not the compiled ftsmc package.

Where the two differ in method (so agreement is not a transliteration):
quaternion products by the left-product matrix ``[q]_L`` (Sola eq. 17),
rotation matrices by Sola eq. 115 and, for the attitude-error transition,
by Rodrigues' formula (eq. 77); the process noise as ``F_i Q_i F_iᵀ``
(eq. 269-271); the magnetometer Jacobian by Sola's chain rule
``H = H_x X_δx`` (eq. 278-281, with eq. 174 for ``∂(R a)/∂q``) instead of
the closed form ``[Rᵀ m]×``; linear solves by LAPACK; the chi-square gate
threshold from the power series of the regularised lower incomplete gamma
function instead of the closed forms.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

FIXTURE = Path(__file__).resolve().parents[2] / "crates" / "ftsmc-core" / "tests" / "data" / "eskf-fixture.json"
TOL = 1e-9


def skew(v):
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def left(q):
    """[q]_L with q ⊗ p = [q]_L p (Sola eq. 17-18)."""
    w, x, y, z = q
    return np.array([[w, -x, -y, -z], [x, w, -z, y], [y, z, w, -x], [z, -y, x, w]])


def qmul(a, b):
    return left(a) @ b


def qconj(q):
    return np.array([q[0], -q[1], -q[2], -q[3]])


def rot(q):
    """R(q) = (w² − vᵀv) I + 2 v vᵀ + 2 w [v]× (Sola eq. 115)."""
    w, v = q[0], np.asarray(q[1:])
    return (w * w - v @ v) * np.eye(3) + 2.0 * np.outer(v, v) + 2.0 * w * skew(v)


def qexp(theta):
    """Exp(θ) (Sola eq. 101)."""
    theta = np.asarray(theta, dtype=float)
    phi = np.linalg.norm(theta)
    if phi < 1e-8:
        return np.concatenate([[1.0 - phi * phi / 8.0], theta / 2.0])
    return np.concatenate([[math.cos(phi / 2.0)], math.sin(phi / 2.0) * theta / phi])


def qlog(q):
    """Log(q), angle in [0, π] (Sola eq. 105)."""
    q = np.asarray(q, dtype=float)
    if q[0] < 0:
        q = -q
    v = q[1:]
    n = np.linalg.norm(v)
    if n < 1e-8:
        return 2.0 * v / q[0]
    return 2.0 * math.atan2(n, q[0]) * v / n


def rodrigues(theta):
    """R{θ} = I cos φ + sin φ [u]× + (1 − cos φ) u uᵀ (Sola eq. 77)."""
    theta = np.asarray(theta, dtype=float)
    phi = np.linalg.norm(theta)
    if phi < 1e-8:
        return np.eye(3) + skew(theta)
    u = theta / phi
    return math.cos(phi) * np.eye(3) + math.sin(phi) * skew(u) + (1.0 - math.cos(phi)) * np.outer(u, u)


def d_rot_a_dq(q, a):
    """∂(R(q) a)/∂q, 3 × 4 (Sola eq. 174)."""
    w, v = q[0], np.asarray(q[1:])
    a = np.asarray(a)
    first = w * a + np.cross(v, a)
    rest = (v @ a) * np.eye(3) + np.outer(v, a) - np.outer(a, v) - w * skew(a)
    return 2.0 * np.column_stack([first, rest])


def chi2_cdf(x, k):
    """P(k/2, x/2) by its power series e^{−y} yᵃ Σ yⁿ/Γ(a+n+1)."""
    a, y = k / 2.0, x / 2.0
    term = math.exp(-y + a * math.log(y) - math.lgamma(a + 1.0))
    total = 0.0
    n = 0
    while term > 1e-18 * max(total, 1e-300) or n < 5:
        total += term
        n += 1
        term *= y / (a + n)
    return total


def chi2_quantile(p, k):
    lo, hi = 0.0, 1.0
    while chi2_cdf(hi, k) < p:
        hi *= 2.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if chi2_cdf(mid, k) < p:
            lo = mid
        else:
            hi = mid
    return hi


class Eskf:
    """Nominal x = (p, v, q, a_b... here b_g, b_a); error δx = [δp, δv, δθ, δb_g, δb_a]."""

    def __init__(self, config, initial):
        self.c = config
        self.p = np.array(initial["position"], dtype=float)
        self.v = np.array(initial["velocity"], dtype=float)
        q = np.array(initial["quaternion"], dtype=float)
        self.q = q / np.linalg.norm(q)
        self.bg = np.array(initial["gyro_bias"], dtype=float)
        self.ba = np.array(initial["accel_bias"], dtype=float)
        stds = [
            config["initial_position_std"],
            config["initial_velocity_std"],
            config["initial_attitude_std"],
            config["initial_gyro_bias_std"],
            config["initial_accel_bias_std"],
        ]
        self.P = np.diag(np.repeat(np.square(stds), 3))
        self.g = np.array([0.0, 0.0, -config["gravity"]])
        self.m_world = np.array(config["magnetic_field"], dtype=float)
        self.time = None
        self.gated_out = 0

    def predict(self, t, wm, am):
        if self.time is None:
            self.time = t
            return
        dt = t - self.time
        self.time = t
        w = np.asarray(wm) - self.bg
        a = np.asarray(am) - self.ba
        R = rot(self.q)
        acc = R @ a + self.g
        # Sola eq. 260 (nominal) and 269-271 (error state).
        Fx = np.eye(15)
        Fx[0:3, 3:6] = np.eye(3) * dt
        Fx[3:6, 6:9] = -R @ skew(a) * dt
        Fx[3:6, 12:15] = -R * dt
        Fx[6:9, 6:9] = rodrigues(w * dt).T
        Fx[6:9, 9:12] = -np.eye(3) * dt
        Fi = np.zeros((15, 12))
        Fi[3:15, :] = np.eye(12)
        c = self.c
        Qi = np.diag(
            np.repeat(
                [
                    c["accel_noise"] ** 2 * dt,
                    c["gyro_noise"] ** 2 * dt,
                    c["gyro_bias_random_walk"] ** 2 * dt,
                    c["accel_bias_random_walk"] ** 2 * dt,
                ],
                3,
            )
        )
        self.p = self.p + self.v * dt + 0.5 * acc * dt * dt
        self.v = self.v + acc * dt
        q = qmul(self.q, qexp(w * dt))
        self.q = q / np.linalg.norm(q)
        P = Fx @ self.P @ Fx.T + Fi @ Qi @ Fi.T
        self.P = 0.5 * (P + P.T)

    def update(self, y, H, V):
        """Sola eq. 274-276 (Joseph form), 282-283 (injection), 285-287 (reset)."""
        y = np.asarray(y, dtype=float)
        S = H @ self.P @ H.T + V
        nis = float(y @ np.linalg.solve(S, y))
        threshold = chi2_quantile(self.c["gate_probability"], len(y))
        accepted = nis <= threshold
        if not accepted:
            self.gated_out += 1
            return nis, threshold, accepted
        K = self.P @ H.T @ np.linalg.inv(S)
        dx = K @ y
        A = np.eye(15) - K @ H
        P = A @ self.P @ A.T + K @ V @ K.T
        self.p = self.p + dx[0:3]
        self.v = self.v + dx[3:6]
        q = qmul(self.q, qexp(dx[6:9]))
        self.q = q / np.linalg.norm(q)
        self.bg = self.bg + dx[9:12]
        self.ba = self.ba + dx[12:15]
        G = np.eye(15)
        G[6:9, 6:9] = np.eye(3) - skew(0.5 * dx[6:9])
        P = G @ P @ G.T
        self.P = 0.5 * (P + P.T)
        return nis, threshold, accepted

    def gnss(self, s):
        y = np.concatenate([np.subtract(s["position"], self.p), np.subtract(s["velocity"], self.v)])
        H = np.zeros((6, 15))
        H[0:3, 0:3] = np.eye(3)
        H[3:6, 3:6] = np.eye(3)
        V = np.diag(np.square(np.concatenate([s["position_std"], s["velocity_std"]])))
        return y, self.update(y, H, V)

    def baro(self, s):
        y = np.array([s["altitude"] - self.p[2]])
        H = np.zeros((1, 15))
        H[0, 2] = 1.0
        return y, self.update(y, H, np.array([[s["std"] ** 2]]))

    def mag(self, s):
        # h(q) = R(q)ᵀ m = R(q*) m; ∂h/∂q = ∂(R(q*) m)/∂q* · diag(1, −1, −1, −1).
        h = rot(self.q).T @ self.m_world
        Hx = d_rot_a_dq(qconj(self.q), self.m_world) @ np.diag([1.0, -1.0, -1.0, -1.0])
        # X_δθ = ∂(q ⊗ δq)/∂δθ = ½ [q]_L [0; I₃] (Sola eq. 281).
        X = 0.5 * left(self.q) @ np.vstack([np.zeros((1, 3)), np.eye(3)])
        H = np.zeros((3, 15))
        H[:, 6:9] = Hx @ X
        y = np.subtract(s["field"], h)
        return y, self.update(y, H, np.eye(3) * s["std"] ** 2)

    def mocap(self, s):
        qm = np.asarray(s["quaternion"], dtype=float)
        qm = qm / np.linalg.norm(qm)
        y = np.concatenate([np.subtract(s["position"], self.p), qlog(qmul(qconj(self.q), qm))])
        H = np.zeros((6, 15))
        H[0:3, 0:3] = np.eye(3)
        H[3:6, 6:9] = np.eye(3)
        V = np.diag([s["position_std"] ** 2] * 3 + [s["attitude_std"] ** 2] * 3)
        return y, self.update(y, H, V)


def close(name, step, got, want):
    got = np.asarray(got, dtype=float)
    want = np.asarray(want, dtype=float)
    err = np.max(np.abs(got - want) / np.maximum(1.0, np.abs(want)))
    assert err <= TOL, f"step {step} ({name}): numpy {got} vs Rust {want}, scaled difference {err:.3e}"
    return err


def test_numpy_eskf_agrees_with_the_rust_fixture_on_every_step():
    data = json.loads(FIXTURE.read_text())
    steps = data["steps"]
    kinds = {s["kind"] for s in steps}
    assert kinds == {"imu", "gnss", "baro", "mag", "mocap"}
    assert sum(s["kind"] == "imu" for s in steps) >= 200
    assert sum(s["kind"] == "gnss" for s in steps) >= 10
    f = Eskf(data["config"], data["initial"])
    iu = np.triu_indices(15)
    worst = 0.0
    rejected = 0
    for n, s in enumerate(steps):
        kind = s["kind"]
        if kind == "imu":
            f.predict(s["time"], s["gyro"], s["specific_force"])
        else:
            y, (nis, threshold, accepted) = getattr(f, kind)(s)
            r = s["report"]
            assert accepted == r["accepted"], f"step {n} ({kind}): gate decision differs, NIS {nis} vs {r['nis']}"
            rejected += not accepted
            worst = max(worst, close("innovation", n, y, r["innovation"]))
            worst = max(worst, close("nis", n, nis, r["nis"]))
            worst = max(worst, close("threshold", n, threshold, r["threshold"]))
        st = s["state"]
        for name, value in [
            ("position", f.p),
            ("velocity", f.v),
            ("gyro_bias", f.bg),
            ("accel_bias", f.ba),
        ]:
            worst = max(worst, close(name, n, value, st[name]))
        # q and −q are the same attitude; both filters keep w continuous, so compare directly.
        worst = max(worst, close("quaternion", n, f.q, st["quaternion"]))
        worst = max(worst, close("covariance", n, f.P[iu], st["covariance_upper"]))
        assert f.gated_out == st["gated_out"]
    assert rejected >= 1, "the fixture's 50-sigma GNSS fix was accepted"
    print(f"{len(steps)} steps, worst scaled difference {worst:.3e}")


if __name__ == "__main__":  # pragma: no cover
    pytest.main([__file__, "-q", "-s"])
