"""Reference floor of the compiled path: the Newton iteration of direct kinematics in one njit function.

The offset-Cardan presets' iteration (the package's algorithm and Schur step, the per-leg chain
kinematics written out), with cold and warm batch loops. Not part of the package: the benchmarks
(``startup.py --cold``, ``floor_compare.py``) run it beside the package's compiled path, in the
same process or the same conditions, to show what the package's structure costs on top.
"""

import numpy as np
from numba import njit

from hexapod_model.kinematics.newton import structured as linalg

_TYPES = {
    "JointModelRX": (0, 0),
    "JointModelRY": (0, 1),
    "JointModelRZ": (0, 2),
    "JointModelPZ": (1, 2),
    "JointModelPX": (1, 0),
    "JointModelPY": (1, 1),
}


def extract(h):
    clm = h.closed_loop
    m = clm.model
    JR = np.zeros((6, 6, 3, 3))
    Jp = np.zeros((6, 6, 3))
    jt = np.zeros((6, 6), np.int64)
    ja = np.zeros((6, 6), np.int64)
    tR = np.zeros((6, 3, 3))
    tp = np.zeros((6, 3))
    aR = np.zeros((6, 3, 3))
    ap = np.zeros((6, 3))
    held = np.zeros(6, np.int64)
    for i, leg in enumerate(clm.legs):
        assert len(leg.joints) == 6 and m.parents[leg.joints[0]] == 0
        for k, j in enumerate(leg.joints):
            assert m.joints[j].idx_v == 6 * i + k
            JR[i, k] = m.jointPlacements[j].rotation
            Jp[i, k] = m.jointPlacements[j].translation
            jt[i, k], ja[i, k] = _TYPES[m.joints[j].shortname()]
            if j == leg.prismatic:
                held[i] = k
        f = m.frames[leg.tip_frame]
        assert f.parentJoint == leg.joints[-1]
        tR[i] = f.placement.rotation
        tp[i] = f.placement.translation
        f = m.frames[leg.anchor_frame]
        aR[i] = f.placement.rotation
        ap[i] = f.placement.translation
    return JR, Jp, jt, ja, tR, tp, aR, ap, held


@njit(cache=True, fastmath=False)
def _exp3(w, out):
    th2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2]
    th = np.sqrt(th2)
    if th < 1e-8:
        a, b = 1.0 - th2 / 6.0, 0.5 - th2 / 24.0
    else:
        a, b = np.sin(th) / th, (1.0 - np.cos(th)) / th2
    x, y, z = w[0], w[1], w[2]
    out[0, 0] = 1 - b * (y * y + z * z)
    out[0, 1] = -a * z + b * x * y
    out[0, 2] = a * y + b * x * z
    out[1, 0] = a * z + b * x * y
    out[1, 1] = 1 - b * (x * x + z * z)
    out[1, 2] = -a * x + b * y * z
    out[2, 0] = -a * y + b * x * z
    out[2, 1] = a * x + b * y * z
    out[2, 2] = 1 - b * (x * x + y * y)
    # V(w) for exp6 translation
    if th < 1e-8:
        c = 1.0 / 6.0 - th2 / 120.0
    else:
        c = (th - np.sin(th)) / (th2 * th)
    return a, b, c


@njit(cache=True)
def fk_newton(theta, Rp, pp, lengths, JR, Jp, jt, ja, tR, tp, aR, ap, held, tol, max_iter, max_step, work_J, out_G):
    """Theta (6,6) leg joint values, Rp/pp platform world pose (updated in place). Returns (iters, norm)."""
    rows = 6
    for i in range(6):
        theta[i, held[i]] = lengths[i]
    J = work_J  # 6 x 42, WORLD convention [v_o; w]
    p = np.empty((12, 3))
    R = np.empty((12, 3, 3))
    E = np.empty((6, 3, 3))
    r = np.empty(36)
    leg_cols = np.empty((6, 6), np.int64)
    ff_cols = np.arange(36, 42)
    colmap = np.empty(42, np.int64)
    held_pos = held.copy()
    c = 0
    for i in range(6):
        for k in range(6):
            leg_cols[i, k] = 6 * i + k
            if k == held[i]:
                colmap[6 * i + k] = -1
            else:
                colmap[6 * i + k] = c
                c += 1
    for k in range(6):
        colmap[36 + k] = c
        c += 1
    x = np.empty(36)
    LB = np.empty((6, 6, 6))
    PB = np.empty((6, 6), np.int64)
    A = np.empty((6, 6, 6))
    M = np.empty((6, 6))
    pm = np.empty(6, np.int64)
    nb = np.empty(6)
    wb = np.empty(6)
    MR = np.empty((3, 3))
    Mp = np.empty(3)
    T = np.empty((3, 3))
    dR = np.empty((3, 3))
    w = np.empty(3)
    it = 0
    norm = 0.0
    while True:
        # ---- kinematics of the six chains ----
        for i in range(6):
            for a in range(3):
                Mp[a] = 0.0
                for b in range(3):
                    MR[a, b] = 1.0 if a == b else 0.0
            for k in range(6):
                # M = M * JP
                for a in range(3):
                    Mp[a] += MR[a, 0] * Jp[i, k, 0] + MR[a, 1] * Jp[i, k, 1] + MR[a, 2] * Jp[i, k, 2]
                for a in range(3):
                    for b in range(3):
                        T[a, b] = MR[a, 0] * JR[i, k, 0, b] + MR[a, 1] * JR[i, k, 1, b] + MR[a, 2] * JR[i, k, 2, b]
                ax = ja[i, k]
                col = 6 * i + k
                t = theta[i, k]
                if jt[i, k] == 0:
                    wx, wy, wz = T[0, ax], T[1, ax], T[2, ax]
                    J[0, col] = Mp[1] * wz - Mp[2] * wy
                    J[1, col] = Mp[2] * wx - Mp[0] * wz
                    J[2, col] = Mp[0] * wy - Mp[1] * wx
                    J[3, col] = wx
                    J[4, col] = wy
                    J[5, col] = wz
                    cs, sn = np.cos(t), np.sin(t)
                    b1, b2 = (ax + 1) % 3, (ax + 2) % 3
                    for a in range(3):
                        MR[a, ax] = T[a, ax]
                        MR[a, b1] = cs * T[a, b1] + sn * T[a, b2]
                        MR[a, b2] = -sn * T[a, b1] + cs * T[a, b2]
                else:
                    for a in range(3):
                        J[a, col] = T[a, ax]
                        J[3 + a, col] = 0.0
                        Mp[a] += t * T[a, ax]
                        for b in range(3):
                            MR[a, b] = T[a, b]
            # tip frame
            for a in range(3):
                p[i, a] = Mp[a] + MR[a, 0] * tp[i, 0] + MR[a, 1] * tp[i, 1] + MR[a, 2] * tp[i, 2]
                for b in range(3):
                    R[i, a, b] = MR[a, 0] * tR[i, 0, b] + MR[a, 1] * tR[i, 1, b] + MR[a, 2] * tR[i, 2, b]
            # anchor frame on the platform
            for a in range(3):
                p[6 + i, a] = pp[a] + Rp[a, 0] * ap[i, 0] + Rp[a, 1] * ap[i, 1] + Rp[a, 2] * ap[i, 2]
                for b in range(3):
                    R[6 + i, a, b] = Rp[a, 0] * aR[i, 0, b] + Rp[a, 1] * aR[i, 1, b] + Rp[a, 2] * aR[i, 2, b]
        # platform columns: Ad(oMp)
        for k in range(3):
            for a in range(3):
                J[a, 36 + k] = Rp[a, k]
                J[3 + a, 36 + k] = 0.0
            wx, wy, wz = Rp[0, k], Rp[1, k], Rp[2, k]
            J[0, 39 + k] = pp[1] * wz - pp[2] * wy
            J[1, 39 + k] = pp[2] * wx - pp[0] * wz
            J[2, 39 + k] = pp[0] * wy - pp[1] * wx
            J[3, 39 + k] = wx
            J[4, 39 + k] = wy
            J[5, 39 + k] = wz
        # ---- residual (as kernels.residual) ----
        min_trace = 3.0
        for i in range(6):
            o = i * 6
            for a in range(3):
                r[o + a] = p[i, a] - p[6 + i, a]
            for a in range(3):
                for b in range(3):
                    E[i, a, b] = R[i, a, 0] * R[6 + i, b, 0] + R[i, a, 1] * R[6 + i, b, 1] + R[i, a, 2] * R[6 + i, b, 2]
            r[o + 3] = 0.5 * (E[i, 2, 1] - E[i, 1, 2])
            r[o + 4] = 0.5 * (E[i, 0, 2] - E[i, 2, 0])
            r[o + 5] = 0.5 * (E[i, 1, 0] - E[i, 0, 1])
            tr = E[i, 0, 0] + E[i, 1, 1] + E[i, 2, 2]
            min_trace = min(min_trace, tr)
        s = 0.0
        for k in range(36):
            s += r[k] * r[k]
        norm = np.sqrt(s)
        if norm <= tol or it >= max_iter or not norm < np.inf:
            break
        ratio, kappa = linalg.schur_solve(
            J, leg_cols, held_pos, ff_cols, colmap, rows, p, E, r, x, LB, PB, A, M, pm, nb, wb, 1.0
        )
        if abs(ratio) < 1e-13:
            return -1, norm
        biggest = 0.0
        for k in range(36):
            biggest = max(biggest, abs(x[k]))
        scale = 1.0 if biggest <= max_step else max_step / biggest
        for i in range(6):
            for k in range(6):
                cc = colmap[6 * i + k]
                if cc >= 0:
                    theta[i, k] -= scale * x[cc]
        # platform: oMp <- oMp * exp6(v), v = -scale * x[ff]
        v0 = -scale * x[colmap[36]]
        v1 = -scale * x[colmap[37]]
        v2 = -scale * x[colmap[38]]
        w[0] = -scale * x[colmap[39]]
        w[1] = -scale * x[colmap[40]]
        w[2] = -scale * x[colmap[41]]
        a_, b_, c_ = _exp3(w, dR)
        # V = I + b [w] + c [w]^2  ; t = V v
        wx, wy, wz = w[0], w[1], w[2]
        cx = wy * v2 - wz * v1
        cy = wz * v0 - wx * v2
        cz = wx * v1 - wy * v0
        ccx = wy * cz - wz * cy
        ccy = wz * cx - wx * cz
        ccz = wx * cy - wy * cx
        t0 = v0 + b_ * cx + c_ * ccx
        t1 = v1 + b_ * cy + c_ * ccy
        t2 = v2 + b_ * cz + c_ * ccz
        for a in range(3):
            pp[a] += Rp[a, 0] * t0 + Rp[a, 1] * t1 + Rp[a, 2] * t2
        for a in range(3):
            for b in range(3):
                T[a, b] = Rp[a, 0] * dR[0, b] + Rp[a, 1] * dR[1, b] + Rp[a, 2] * dR[2, b]
        for a in range(3):
            for b in range(3):
                Rp[a, b] = T[a, b]
        it += 1
    return it, norm


@njit(cache=True)
def fk_batch_warm(
    L, theta0, Rp0, pp0, JR, Jp, jt, ja, tR, tp, aR, ap, held, tol, max_iter, max_step, out_R, out_p, out_it
):
    """Sequential warm-started FK over a trajectory (each solve from the previous)."""
    theta = theta0.copy()
    Rp = Rp0.copy()
    pp = pp0.copy()
    J = np.zeros((6, 42))
    G = np.zeros((1, 1))
    for n in range(L.shape[0]):
        it, nrm = fk_newton(theta, Rp, pp, L[n], JR, Jp, jt, ja, tR, tp, aR, ap, held, tol, max_iter, max_step, J, G)
        out_R[n] = Rp
        out_p[n] = pp
        out_it[n] = it


@njit(cache=True)
def fk_batch_cold(L, JR, Jp, jt, ja, tR, tp, aR, ap, held, Rh, ph, tol, max_iter, max_step, out_R, out_p, out_it):
    """Independent FK of each row, each from home."""
    J = np.zeros((6, 42))
    G = np.zeros((1, 1))
    for n in range(L.shape[0]):
        theta = np.zeros((6, 6))
        Rp = Rh.copy()
        pp = ph.copy()
        it, nrm = fk_newton(theta, Rp, pp, L[n], JR, Jp, jt, ja, tR, tp, aR, ap, held, tol, max_iter, max_step, J, G)
        out_R[n] = Rp
        out_p[n] = pp
        out_it[n] = it
