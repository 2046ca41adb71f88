#!/usr/bin/env python3
"""1-DoF model of the pmi-pd tick on a quantised device pressed by a grip hand (issue #29 item 2;
docs/derivations/quiet_stiffness.md).

One axis z, the tick's equations at 1 kHz (reference/tick.cc, 1-DoF):
  device + hand (true plant, RK4 substeps, force held over the tick):
      (m_d + m_h) z'' = T1 - b_d z' + K_h (z_ref - z) - B_h z' + f_ff
  driver: z_q = Delta floor(z / Delta); v_m = 200 Hz first-order low-pass of the backward difference
  momentum observer (gripped hypothesis, M1 = m_d + m_h, gain L): p = M1 v_m,
      p_hat += T (T1_prev + f_hat);  f_hat = L (p - p_hat)
  decomposition: M_L = M1 + m2, phi = m2 / M_L, A = M_L / M_d,
      X(V) = A (f_hat + F2(V) - D_d v_L(V)),  v_L = (1 - phi) v_m + phi V
  proxy (PMI, implicit midpoint, affine in V): m2 (V_next - V) / T = F_c(V) + phi X(V),
      F_c = K_vc (z_q - z2) + B_vc (v_m - V), F2 = K (s - z2) - b_t V in contact (z2 < s)
  device command: T1 = -F_c + (1 - phi) X - f_hat
Options switch one thing at a time: --no-quant, --k, --md, --cutoff (velocity low-pass, 0 = raw
backward difference), --L, and the remedies under study: --kalman SIGMA_F (the encoder Kalman
filter of reference/encoder_kalman.h, with the observer on its velocity as in the tick),
--cell-coupling (the coupling sees the point of the encoder cell nearest the proxy), --foaw N
(first-order adaptive windowing velocity), --bt (tooth damping); for the stiff contact mode
(docs/derivations/quiet_stiffness.md section 5): --pc raw|allow (a passivity observer/controller on
the device port, with the encoder-error allowance), --eb (energy bounding), --lead (loop-lag
compensation, reference/lag_compensation.h), --contact-zeta (damping in contact), and the
diagnostics --ideal-obs / --freeze-obs. --grid2 runs the stiff grid (K 6000-18000 N/m). Beyond the
staircase (section 8): --setmember SIGMA_F (a set-membership estimate, SetMember: the model's
prediction kept while it is inside the encoder cell, corrected only at the cell's bounds), with
--sm-snap 0|1, --sm-cap 0|1, --sm-pos-only; --coulomb F (the device's Coulomb friction), --kh,
--bh (the hand's stiffness and damping: a 1-DoF reduction of another axis, e.g. the gimbal pitch);
--estimate-stats and --dump FILE (the tick's series) for diagnosis.

Prints the quiet measures of the held press (t in [1.5, 3.0] s): ripple of the contact force and of
the device force (RMS minus 0.1 s moving average, over the mean), contact fraction, losses, static
stiffness, and with --free the RMS device force while the hand moves in free space.
"""
import argparse
import math

import numpy as np


def ripple(x, n=100):
    avg = np.convolve(x, np.ones(n) / n, mode="valid")
    core = x[n // 2:n // 2 + len(avg)]
    m = np.mean(core)
    return float(np.sqrt(np.mean((core - avg) ** 2)) / m) if m > 0 else float("nan")


def foaw(hist, T, d, nmax):
    """First-order adaptive windowing (Janabi-Sharifi et al. 2000), end-fit: the longest window
    n <= nmax whose straight line through y_k and y_k-n passes within d of every sample between."""
    y = hist
    k = len(y) - 1
    best = 0.0
    for n in range(1, min(nmax, k) + 1):
        v = (y[k] - y[k - n]) / (n * T)
        ok = True
        for j in range(1, n):
            if abs(y[k - j] - (y[k] - v * j * T)) > d:
                ok = False
                break
        if not ok:
            break
        best = v
    return best


class AlphaBeta:
    """Steady-state Kalman filter of a double integrator driven by the model's acceleration
    (commanded force + observer estimate over the mass); measurement z_q + Delta/2 with variance
    Delta^2/12; process noise: the unknown force sigma_f over the mass (white acceleration)."""

    def __init__(self, delta, T, sigma_a, project):
        import numpy as _np
        F = _np.array([[1, T], [0, 1]]); H = _np.array([[1.0, 0.0]])
        G = _np.array([[0.5 * T * T], [T]])
        Q = G @ G.T * sigma_a ** 2
        R = delta ** 2 / 12
        P = _np.eye(2) * 1e-6
        for _ in range(20000):
            P = F @ P @ F.T + Q
            S = H @ P @ H.T + R
            K = P @ H.T / S
            P = (_np.eye(2) - K @ H) @ P
        self.K = K.ravel()
        self.T = T
        self.d = delta
        self.project = project
        self.z = None
        self.v = 0.0

    def update(self, zq, a_pred, T):
        if self.z is None:
            self.z = zq + 0.5 * self.d
            return self.z, 0.0
        z = self.z + T * self.v + 0.5 * T * T * a_pred
        v = self.v + T * a_pred
        r = (zq + 0.5 * self.d) - z
        z += self.K[0] * r
        v += self.K[1] * r
        if self.project:
            z = min(max(z, zq), zq + self.d)
        self.z, self.v = z, v
        return z, v


class SetMember:
    """Set-membership estimate of (z, v) from an incremental encoder, predicted with the model's
    acceleration like AlphaBeta, but with no pull toward the cell's centre: the count says only
    that z lies in the cell [z_q, z_q + Delta], so a prediction inside the cell is kept as it is.
    Two corrections, each a Kalman update with the prediction's covariance P (process noise the
    unknown force sigma_a, as AlphaBeta):
      - a count transition: the truth crossed the boundary b between the cells during the tick
        that ended, at an instant uniform over it, so z(t_k) = b + v tau, tau ~ U(0, T):
        measurement b + v- T / 2 with variance (v- T)^2 / 12;
      - a prediction outside the cell without a transition: projected onto the nearest bound
        (an exact measurement of the bound, the estimate projection of a constrained Kalman
        filter), the velocity corrected by P_vz / P_zz times the projection.
    At rest (a = 0, no transition) every point of the cell is a rest state."""

    def __init__(self, delta, T, sigma_a, cap=True, snap=True):
        self.snap = snap
        import numpy as _np
        self.np = _np
        self.F = _np.array([[1, T], [0, 1]])
        G = _np.array([[0.5 * T * T], [T]])
        self.Q = G @ G.T * sigma_a ** 2
        self.d = delta
        self.T = T
        self.cap = cap
        self.z = None
        self.v = 0.0
        self.P = _np.diag([delta ** 2 / 12, 0.0])
        self.zq_prev = None

    def _update(self, y, R):
        P = self.P
        S = P[0, 0] + R
        if S <= 0:
            return
        Kz, Kv = P[0, 0] / S, P[1, 0] / S
        r = y - self.z
        self.z += Kz * r
        self.v += Kv * r
        KH = self.np.array([[Kz, 0.0], [Kv, 0.0]])
        self.P = (self.np.eye(2) - KH) @ P

    def update(self, zq, a_pred, T):
        if self.z is None:
            self.z = zq + 0.5 * self.d
            self.zq_prev = zq
            return self.z, 0.0
        d = self.d
        self.z = self.z + T * self.v + 0.5 * T * T * a_pred
        self.v = self.v + T * a_pred
        self.P = self.F @ self.P @ self.F.T + self.Q
        if self.snap and zq != self.zq_prev:
            b = zq if zq > self.zq_prev else zq + d
            y = min(max(b + 0.5 * self.v * T, zq), zq + d)
            self._update(y, (self.v * T) ** 2 / 12 + (1e-6 * d) ** 2)
        lo, hi = zq, zq + d
        if self.z < lo or self.z > hi:
            y = min(max(self.z, lo), hi)
            self._update(y, 0.0)
            self.z = y
        if self.cap and self.P[0, 0] > d * d / 12:
            # the cell bounds the position's spread (uniform over the cell at most)
            c = math.sqrt(d * d / 12 / self.P[0, 0])
            self.P[0, 0] *= c * c
            self.P[0, 1] *= c
            self.P[1, 0] *= c
        self.zq_prev = zq
        return self.z, self.v


def run(a):
    T = 1e-3
    n_sub = 8
    md, mh = a.mdev, a.mh
    Kh, Bh, bd = a.kh, a.bh, 0.0125
    m2, Kvc, Bvc = 0.05, 1200.0, a.bvc
    M1 = md + mh
    ML = M1 + m2
    phi = m2 / ML
    Md = a.md if a.md > 0 else ML + a.md_extra  # the preset's rule: M_L (with the hand) + instrument
    A = ML / Md
    Dd, K, bt = a.dd, a.k, a.bt
    L = a.L
    delta = 0.0 if a.no_quant else a.delta
    s = 0.0  # surface
    nT = int(a.duration / T)
    # hand profile: free-space move 0-1 s (5 mm/s back and forth about 6 mm up), lower 1-1.5 s,
    # press with f_ff held at the surface after 1.5 s
    def href(t):
        if t < 1.0:
            return 6e-3 + 2e-3 * math.sin(2 * math.pi * 1.0 * t), 0.0
        if t < 1.5:
            return 6e-3 * (1.5 - t) / 0.5, -a.press * (t - 1.0) / 0.5
        if a.kick and 2.0 <= t < 2.002:  # a 2 ms, 0.2 N push: rings the contact mode
            return 0.0, -a.press - 0.2
        return 0.0, -a.press

    z, v = 6e-3, 0.0
    z2, v2 = z, 0.0
    zq_prev = z if delta == 0 else delta * math.floor(z / delta)
    vm = 0.0
    hist = []
    vt, z_prev_true = 0.0, z
    p_hat = 0.0
    f_hat = 0.0
    T1 = 0.0
    sc = None
    if a.kalman > 0 and delta > 0:
        sc = AlphaBeta(delta, T, a.kalman / M1, a.project)
    sc_vel = None
    if a.setmember > 0 and delta > 0 and a.sm_pos_only:
        sc_vel = AlphaBeta(delta, T, a.setmember / M1, a.project)
    if a.setmember > 0 and delta > 0:
        sc = SetMember(delta, T, a.setmember / M1, cap=bool(a.sm_cap), snap=bool(a.sm_snap))
    fc_log, fd_log, inc_log, pen_log, t_log = [], [], [], [], []
    dump_log = []
    ea_true_log, ea_count_log, dT1_log = [], [], []
    T1_log_prev, zq_log_prev, T1_first_prev = 0.0, zq_prev, 0.0
    # passivity observer/controller state (--pc): the energy the controller has absorbed at the
    # device port, from the displacement the driver reports, and the encoder-error allowance
    E_obs, E_allow, zs_prev, T1_cmd_prev, pc_energy, pc_fire, pc_tv = 0.0, 0.0, None, 0.0, 0.0, 0, 0.0
    alpha_max = a.pc_max if a.pc_max > 0 else md / T  # default: the largest damping an explicit tick applies stably to the device alone
    alpha = 1.0 - math.exp(-2 * math.pi * a.cutoff * T) if a.cutoff > 0 else 1.0
    fcoul, vs_coul = a.coulomb, 1e-4  # the device's Coulomb friction, smoothed over 0.1 mm/s
    for k in range(nT):
        t = k * T
        zq = z if delta == 0 else delta * math.floor(z / delta)
        vraw = (zq - zq_prev) / T
        zq_prev = zq
        vm = vm + alpha * (vraw - vm)
        hist.append(zq)
        vf = foaw(hist, T, delta, a.foaw) if a.foaw > 0 and delta > 0 else None
        if vf is not None and a.foaw_where == "all":
            vm = vf
        vt = vt + alpha * ((z - z_prev_true) / T - vt)  # the same estimator on the true position
        z_prev_true = z
        zs, vs = zq, vm
        if "pos" not in a.quant_in:
            zs = z
        if "vel" not in a.quant_in:
            vs = vt
        if sc is not None:
            a_pred = (T1 + f_hat) / M1
            zs, vs = sc.update(zq, a_pred, T)
            if sc_vel is not None:  # --sm-pos-only: the Kalman filter's velocity, SetMember's position
                _, vs = sc_vel.update(zq, a_pred, T)
            if not a.subcount_vel:
                vs = vm
        if a.cell_coupling and delta > 0:
            # remedy under study: the device position the coupling sees is the point of the
            # encoder cell [z_q, z_q + Delta) nearest the proxy
            zs = min(max(z2, zq), zq + delta)
        vc = vs
        if vf is not None and a.foaw_where == "coupling":
            vc = vf
        if a.lead:
            # lag compensation: the velocity the coupling damper and D_d see is the measured one
            # advanced over the loop's known lags with the model's acceleration (the command over
            # the tick that ended plus the observer's estimate, over M1): the zero-order hold's
            # T/2, the backward difference's T/2 and the discrete low-pass's exact lag on a ramp,
            # T (1 - a) / a with a = 1 - exp(-2 pi f_c T)
            lag = 0.5 * T
            if sc is None or not a.subcount_vel:  # the driver's estimate: difference + low-pass
                lag += 0.5 * T + (T * (1 - alpha) / alpha if a.cutoff > 0 else 0.0)
            vc = vs + lag * (T1 + f_hat) / M1
            vs = vc
        # observer
        p = M1 * (vs if (sc is not None and a.obs_subcount) else (vm if "obs" in a.quant_in else vt))
        if k == 0:
            p_hat = p
        p_hat += T * (T1 + f_hat)
        f_hat = L * (p - p_hat)
        if a.ideal_obs:  # diagnostic: the hand's true force, no observer lag
            zr_, fff_ = href(t)
            f_hat = Kh * (zr_ - z) - Bh * v + fff_
        if a.freeze_obs:  # diagnostic: the observer's estimate low-passed at 1 Hz (no loop at 20 Hz)
            f_slow = f_hat if k == 0 else f_slow + (1 - math.exp(-2 * math.pi * T)) * (f_hat - f_slow)
            f_hat_used = f_slow
        else:
            f_hat_used = f_hat
        # proxy step, contact decided at z2 (tick k)
        incontact = z2 < s
        # affine pieces in V: F = f0 + g V
        # PMI midpoint positions: z2_mid = z2 + T/2 V
        Fc0 = Kvc * (zs - z2) + Bvc * vc
        Fcg = -Kvc * T / 2 - Bvc
        bt_k = bt + (2 * a.contact_zeta * math.sqrt(K * Md) if a.contact_zeta > 0 else 0.0)
        if incontact:
            F20, F2g = K * (s - z2), -K * T / 2 - bt_k
        else:
            F20, F2g = 0.0, 0.0
        vL0, vLg = (1 - phi) * vs, phi
        X0 = A * (f_hat_used + F20 - Dd * vL0)
        Xg = A * (F2g - Dd * vLg)
        # m2 (2V - 2 v2)/T = Fc0 + Fcg V + phi (X0 + Xg V)
        lhs = 2 * m2 / T - Fcg - phi * Xg
        V = (2 * m2 / T * v2 + Fc0 + phi * X0) / lhs
        Fc = Fc0 + Fcg * V
        X = X0 + Xg * V
        F2 = F20 + F2g * V
        T1 = -Fc + (1 - phi) * X - f_hat_used
        if a.pc != "none":
            # time-domain passivity observer/controller (Hannaford & Ryu 2002) on the device port,
            # impedance causality: E_obs = -sum T1_(j-1) (z_j - z_(j-1)) from the driver's position
            # (the energy the controller absorbed). The encoder hides at most Delta |T1_n| +
            # Delta sum |T1_j - T1_(j-1)| of it (summation by parts of sum T1 (e_j - e_(j-1)),
            # 0 <= e < Delta): 'allow' fires only past that bound, 'raw' on E_obs < 0.
            if zs_prev is not None:
                E_obs += -T1_cmd_prev * (zs - zs_prev)
            if a.pc == "allow":
                E_allow = delta * (abs(T1_cmd_prev) + pc_tv)
            excess = -(E_obs + (E_allow if a.pc == "allow" else 0.0))
            if excess > 0 and abs(vs) > 0:
                alpha = min(excess / (T * vs * vs), alpha_max)
                f_pc = -alpha * vs
                T1 += f_pc
                pc_fire += 1
                pc_energy += alpha * vs * vs * T
                E_obs += alpha * vs * vs * T
            zs_prev = zs
        if a.eb:
            # energy bounding (Kim & Ryu 2010): the energy the zero-order hold may generate over a
            # tick is bounded by what the device's physical damping b dissipates, 1/2 |dT1 dz| <=
            # b dz^2 / T -> |dT1| <= 2 b |dz| / T (dz from the driver: no change inside a cell)
            dz = (zs - zs_prev) if zs_prev is not None else 0.0
            lim = 2 * bd * abs(dz) / T
            T1 = T1_cmd_prev + max(-lim, min(lim, T1 - T1_cmd_prev)) if zs_prev is not None else T1
            zs_prev = zs
        pc_tv += abs(T1 - T1_cmd_prev)
        T1_cmd_prev = T1
        if a.sat > 0:
            T1 = max(-a.sat, min(a.sat, T1))
        z2, v2 = z2 + T * V, 2 * V - v2
        # plant
        z_before = z
        zr, fff = href(t)
        h = T / n_sub
        for _ in range(n_sub):
            def acc(zz, vv):
                return (T1 - bd * vv + Kh * (zr - zz) - Bh * vv + fff - fcoul * math.tanh(vv / vs_coul)) / M1
            k1v, k1z = acc(z, v), v
            k2v, k2z = acc(z + h / 2 * k1z, v + h / 2 * k1v), v + h / 2 * k1v
            k3v, k3z = acc(z + h / 2 * k2z, v + h / 2 * k2v), v + h / 2 * k2v
            k4v, k4z = acc(z + h * k3z, v + h * k3v), v + h * k3v
            z += h / 6 * (k1z + 2 * k2z + 2 * k3z + k4z)
            v += h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
        if a.dump or a.estimate_stats:
            zr_, fff_ = href(t)
            dump_log.append((t, z, zs, zq, f_hat, Kh * (zr_ - z) + fff_, T1, F2 if incontact else 0.0, vs, v))
        t_log.append(t)
        fc_log.append(abs(F2) if incontact else 0.0)
        fd_log.append(abs(T1))
        inc_log.append(incontact)
        pen_log.append(max(0.0, s - z))
        # the device port's energy absorbed by the controller over this tick: true (the plant's
        # displacement) and as the driver's counts report it (the last tick's command over the
        # last count step)
        ea_true_log.append(-T1 * (z - z_before))
        ea_count_log.append(-T1_log_prev * (zq - zq_log_prev))
        T1_log_prev, zq_log_prev = T1, zq
        dT1_log.append(abs(T1 - T1_first_prev))
        T1_first_prev = T1
    if a.estimate_stats and delta > 0:
        dl = np.array(dump_log)
        sel = dl[:, 0] >= 1.5 + a.settle
        t_, z_, ze_, zq_, fh_, Fh_ = dl[sel, :6].T
        u_ = (ze_ - zq_) / delta
        hist = np.histogram(u_, bins=[0, 1e-6, 0.25, 0.5, 0.75, 1 - 1e-6, 1 + 1e-9])[0] / len(u_)
        print("estimate in its cell [at the lower bound, (0, 1/4), (1/4, 1/2), (1/2, 3/4), (3/4, 1), "
              "at the upper bound]: " + " ".join(f"{x:.2f}" for x in hist) +
              f"; estimate error RMS {1e6 * np.sqrt(np.mean((ze_ - z_) ** 2)):.1f} um"
              f"; count changes {np.sum(np.diff(zq_) != 0) / (t_[-1] - t_[0]):.0f} /s"
              f"; observer error RMS {1e3 * np.sqrt(np.mean((fh_ - Fh_) ** 2)):.1f} mN")
    if a.dump:
        np.savetxt(a.dump, np.array(dump_log), header="t z z_est z_q f_hat F_h_static T1 F2 v_est v")
    t_log = np.array(t_log)
    fc, fd, inc, pen = map(np.array, (fc_log, fd_log, inc_log, pen_log))
    if a.kick:
        # damping ratio and frequency of the ring after the push: log decrement of the peaks of
        # the contact force about its final value
        sel = t_log >= 2.002
        x = fc[sel] - np.mean(fc[t_log >= a.duration - 0.2])
        pk = [i for i in range(1, len(x) - 1) if x[i] > x[i - 1] and x[i] >= x[i + 1] and x[i] > 0]
        amp = [x[i] for i in pk]
        zeta, freq = float("nan"), float("nan")
        big = [j for j in range(len(amp)) if amp[j] > 1e-3 * amp[0]] if amp else []
        if len(big) >= 3:
            n = big[-1]
            delta = math.log(amp[0] / amp[n]) / n
            zeta = delta / math.sqrt(4 * math.pi ** 2 + delta ** 2)
            freq = n / ((pk[n] - pk[0]) * T)
        return {"zeta": zeta, "freq_hz": freq}
    w = (t_log >= 1.5 + a.settle) & (t_log <= a.duration)
    free = (t_log >= 0.2) & (t_log < 1.0)
    out = {
        "ripple_contact": ripple(fc[w]),
        "ripple_device": ripple(fd[w]),
        "contact_fraction": float(np.mean(inc[w])),
        "losses": int(np.sum(inc[w][:-1] & ~inc[w][1:])),
        "k_static": float(np.mean(fc[w]) / np.mean(pen[w])) if np.mean(pen[w]) > 0 else float("nan"),
        "mean_force": float(np.mean(fc[w])),
        "free_rms": float(np.sqrt(np.mean(fd[free] ** 2))),
        "port_true_mW": 1e3 * float(np.mean(np.array(ea_true_log)[w]) / T),
        "port_count_mW": 1e3 * float(np.mean(np.array(ea_count_log)[w]) / T),
        "allow_mW": 1e3 * float(delta * np.mean(np.array(dT1_log)[w]) / T),
        "pc_fired": pc_fire,
        "pc_mJ": 1e3 * pc_energy,
    }
    return out


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--k", type=float, default=3000.0, help="K_tooth [N/m]")
    p.add_argument("--bt", type=float, default=5.0, help="tooth damping [N s/m]")
    p.add_argument("--delta", type=float, default=0.1e-3, help="tip quantum along z [m]")
    p.add_argument("--no-quant", action="store_true")
    p.add_argument("--mdev", type=float, default=0.136, help="device apparent mass along z [kg]")
    p.add_argument("--coulomb", type=float, default=0.0, help="the device's Coulomb friction at the tip [N] (tanh over 0.1 mm/s)")
    p.add_argument("--mh", type=float, default=0.554, help="hand mass [kg]")
    p.add_argument("--kh", type=float, default=135.0, help="hand stiffness K_h [N/m]")
    p.add_argument("--bh", type=float, default=6.45, help="hand damping B_h [N s/m]")
    p.add_argument("--md", type=float, default=0.0, help="desired tool mass M_d [kg] (0: the preset's rule)")
    p.add_argument("--md-extra", type=float, default=0.01, help="instrument mass over M_L [kg] (explorer)")
    p.add_argument("--dd", type=float, default=0.2, help="D_d [N s/m]")
    p.add_argument("--bvc", type=float, default=4.0, help="coupling damping [N s/m]")
    p.add_argument("--L", type=float, default=30.0, help="observer gain [1/s]")
    p.add_argument("--cutoff", type=float, default=200.0, help="velocity low-pass [Hz], 0 = none")
    p.add_argument("--press", type=float, default=0.5, help="hand feed-forward [N]")
    p.add_argument("--sat", type=float, default=0.0, help="force saturation [N] (0 = none)")
    p.add_argument("--duration", type=float, default=3.0)
    p.add_argument("--settle", type=float, default=0.5)
    p.add_argument("--quant-in", default="pos,vel,obs",
                   help="where the quantised signal enters: pos (coupling/contact position), vel "
                        "(coupling and feed-forward velocity), obs (observer momentum)")
    p.add_argument("--cell-coupling", action="store_true", help="remedy: coupling to the encoder cell")
    p.add_argument("--foaw", type=int, default=0, help="velocity: adaptive windowing, max window [ticks] (0 = the low-pass)")
    p.add_argument("--foaw-where", default="all", help="all | coupling")
    p.add_argument("--kalman", type=float, default=0.0, help="remedy: model-based Kalman estimate, sigma of the unknown force [N] (0 = off)")
    p.add_argument("--setmember", type=float, default=0.0, help="remedy: set-membership estimate (SetMember), sigma of the unknown force [N] (0 = off)")
    p.add_argument("--dump", default="", help="write the tick's series (t z z_est z_q f_hat F_h T1 F2 v_est v; F_h the "
                   "hand's spring and feed-forward force, without its damper) to this file")
    p.add_argument("--estimate-stats", action="store_true",
                   help="print where the position estimate sits in its encoder cell, its error, the count "
                        "changes per second and the observer's error (hand's force without its damper) over the held press")
    p.add_argument("--sm-pos-only", action="store_true", help="SetMember's position for the coupling and the contact, the Kalman filter's (AlphaBeta) velocity for the rest")
    p.add_argument("--sm-snap", type=int, default=1, help="SetMember: update at a count transition (the boundary's crossing)")
    p.add_argument("--sm-cap", type=int, default=1, help="SetMember: cap the position variance at Delta^2/12")
    p.add_argument("--project", type=int, default=1, help="project the Kalman estimate into the cell")
    p.add_argument("--subcount-vel", type=int, default=1, help="the coupling and feed-forward use the Kalman velocity too")
    p.add_argument("--obs-subcount", type=int, default=1, help="the observer uses the Kalman velocity (as the tick does)")
    p.add_argument("--pc", default="none", help="passivity observer/controller on the device port: none | raw | allow (with the encoder-error allowance)")
    p.add_argument("--pc-max", type=float, default=0.0, help="the passivity controller's largest damping [N s/m] (0: m_d / T)")
    p.add_argument("--eb", action="store_true", help="energy bounding (Kim & Ryu) with the device's physical damping")
    p.add_argument("--lead", action="store_true", help="lag compensation: the coupling/D_d velocity advanced over the loop's lags with the model")
    p.add_argument("--contact-zeta", type=float, default=0.0, help="contact damping 2 zeta sqrt(K M_d) added in contact (0 = off)")
    p.add_argument("--ideal-obs", action="store_true", help="diagnostic: f_hat = the hand's true force")
    p.add_argument("--freeze-obs", action="store_true", help="diagnostic: f_hat low-passed at 1 Hz in the decomposition")
    p.add_argument("--kick", action="store_true",
                   help="push 0.2 N for 2 ms at t = 2 s and print the damping ratio and frequency "
                        "of the contact mode (log decrement; use with --no-quant)")
    p.add_argument("--grid", action="store_true",
                   help="run K 3000 and 6000 x Delta 0.012, 0.03, 0.06 mm x press 0.5, 1, 2 N with "
                        "the other options; print contact/device ripple [%%]/losses per cell, the "
                        "mean device ripple and the free-space RMS per Delta")
    p.add_argument("--grid2", action="store_true",
                   help="the stiff grid: K 6000, 9000, 12000, 18000 x Delta 0, 0.012, 0.03 mm x press "
                        "0.5, 1, 2 N; per K: mean contact / device ripple [%%], total losses, mean "
                        "static stiffness, worst cell, free RMS per Delta")
    p.add_argument("--cells", action="store_true", help="with --grid2: print every cell")
    a = p.parse_args()
    if a.grid2:
        for k in (6000.0, 9000.0, 12000.0, 18000.0):
            rc, rd, loss, ks, free, worst, fired = [], [], 0, [], [], 0.0, 0
            for d in (0.0, 0.012e-3, 0.03e-3):
                for press in (0.5, 1.0, 2.0):
                    a.k, a.delta, a.press, a.no_quant = k, d, press, d == 0.0
                    o = run(a)
                    rc.append(o["ripple_contact"]); rd.append(o["ripple_device"])
                    loss += o["losses"]; ks.append(o["k_static"]); fired += o["pc_fired"]
                    worst = max(worst, o["ripple_contact"], o["ripple_device"])
                    if a.cells:
                        print(f"  K {k:.0f} Delta {1e3 * d:.3f} mm press {press} N: " + " ".join(
                            f"{kk}={vv:.4g}" if isinstance(vv, float) else f"{kk}={vv}" for kk, vv in o.items()))
                free.append(f"{o['free_rms']:.3f}")
            print(f"K {k:.0f}: ripple contact {100 * np.mean(rc):.1f} % device {100 * np.mean(rd):.1f} % "
                  f"worst {100 * worst:.0f} %; losses {loss}; k_static {np.nanmean(ks):.0f}; free RMS "
                  + " ".join(free) + (f"; pc ticks {fired}" if a.pc != "none" else ""))
        return
    if a.grid:
        for k in (3000.0, 6000.0):
            cells, free, tot = [], [], 0.0
            for d in (0.012e-3, 0.03e-3, 0.06e-3):
                for press in (0.5, 1.0, 2.0):
                    a.k, a.delta, a.press = k, d, press
                    o = run(a)
                    tot += o["ripple_device"]
                    cells.append(f"{100 * o['ripple_contact']:.0f}/{100 * o['ripple_device']:.0f}/{o['losses']}")
                free.append(f"{o['free_rms']:.3f}")
            print(f"K {k:.0f}: mean device ripple {100 * tot / 9:.1f} %; " + " ".join(cells) +
                  "; free RMS [N] " + " ".join(free))
        return
    out = run(a)
    print(" ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in out.items()))


if __name__ == "__main__":
    main()
