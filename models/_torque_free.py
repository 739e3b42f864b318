"""Exact solution of the torque-free rigid body (Euler-Poinsot motion).

Used as the analytic reference of the paper's free-body examples.  The angular
velocity is given by Jacobi elliptic functions (Landau & Lifshitz, Mechanics, sec. 37),
written for any diagonal inertia tensor: in a cyclic relabelling of the principal axes
(a proper rotation, so Euler's equations keep their form) with the intermediate axis
second,

    omega_d = A_d dn(s),  omega_2 = A_2 sn(s),  omega_e = A_e cn(s),   s = lam t + s0,

``d`` the axis the body precesses about (largest inertia if L^2 > 2T I_2, smallest
otherwise), ``e`` the remaining one.  Amplitudes follow from energy and momentum,
signs and ``lam`` from Euler's equations, ``s0`` from the initial value (incomplete
elliptic integral, Carlson's R_F).

The orientation is ``R(t) = P Rz(phi(t)) A(t)``: ``A(t)`` maps the body frame to a frame
whose z axis is the (body) angular momentum direction ``l_b = Theta omega / |L|`` (built
from ``l_b`` and a fixed body axis never parallel to it), ``P`` is constant (fixed by
``R(0)``), and the precession angle obeys ``phi' = omega . l_b + b1' . b2``; it is
integrated with composite Gauss-Legendre quadrature of the closed-form integrand (to
machine precision).  Elliptic functions: arithmetic-geometric mean (Abramowitz &
Stegun 16.4), after reducing the argument modulo the period 4K.
"""
import numpy as np

EPS = np.finfo(float).eps


def agm_K(m):
    """Complete elliptic integral of the first kind K(m), parameter m = k^2 in [0, 1)."""
    a, b = 1.0, np.sqrt(1.0 - m)
    for _ in range(60):
        if abs(a - b) <= 4 * EPS * a:
            break
        a, b = 0.5 * (a + b), np.sqrt(a * b)
    return np.pi / (2.0 * a)


def ellipj(u, m):
    """Jacobi elliptic functions (sn, cn, dn) for arrays ``u``, parameter 0 <= m < 1."""
    u = np.asarray(u, float)
    if m < 0 or m >= 1:
        raise ValueError(f"ellipj: parameter m = {m} outside [0, 1)")
    if m < 1e-300:
        return np.sin(u), np.cos(u), np.ones_like(u)
    K = agm_K(m)
    u = np.mod(u, 4.0 * K)                       # periodicity keeps the phase accurate
    a = [1.0]
    c = [np.sqrt(m)]
    b = np.sqrt(1.0 - m)
    while abs(c[-1]) > EPS * a[-1] and len(a) < 60:
        an = 0.5 * (a[-1] + b)
        cn_ = 0.5 * (a[-1] - b)
        b = np.sqrt(a[-1] * b)
        a.append(an)
        c.append(cn_)
    N = len(a) - 1
    phi = (2.0 ** N) * a[N] * u
    phis = [phi]
    for n in range(N, 0, -1):
        phi = 0.5 * (phi + np.arcsin(np.clip(c[n] / a[n] * np.sin(phi), -1.0, 1.0)))
        phis.append(phi)
    phi0 = phis[-1]
    sn = np.sin(phi0)
    cn = np.cos(phi0)
    # dn > 0 for 0 <= m < 1; the A&S quotient cos(phi0)/cos(phi1 - phi0) is 0/0 at u = K
    dn = np.sqrt(1.0 - m * sn * sn)
    return sn, cn, dn


def carlson_rf(x, y, z):
    """Carlson's symmetric integral R_F(x, y, z) (duplication algorithm)."""
    for _ in range(100):
        lam = np.sqrt(x * y) + np.sqrt(y * z) + np.sqrt(z * x)
        x, y, z = 0.25 * (x + lam), 0.25 * (y + lam), 0.25 * (z + lam)
        mu = (x + y + z) / 3.0
        dx, dy, dz = 1 - x / mu, 1 - y / mu, 1 - z / mu
        if max(abs(dx), abs(dy), abs(dz)) < 1e-4:
            break
    e2 = dx * dy - dz * dz
    e3 = dx * dy * dz
    return (1 - e2 / 10 + e3 / 14 + e2 * e2 / 24 - 3 * e2 * e3 / 44) / np.sqrt(mu)


def ellipf(phi, m):
    """Incomplete elliptic integral of the first kind F(phi | m), any real phi."""
    K = agm_K(m)
    n = np.round(phi / np.pi)
    p = phi - n * np.pi                           # in [-pi/2, pi/2]
    s = np.sin(p)
    return s * carlson_rf(np.cos(p) ** 2, 1 - m * s * s, 1.0) + 2 * n * K


def _gauss_legendre(n=16):
    x, w = np.polynomial.legendre.leggauss(n)
    return x, w


class TorqueFreeRotation:
    """Exact rotation of a torque-free rigid body about its centre of mass.

    ``inertia``: principal moments about the COM (the body axes must be principal
    axes; all three distinct unless ``omega0`` lies along a principal axis);
    ``R0``: initial rotation (body -> world); ``omega0``: initial BODY-FIXED angular
    velocity.  ``omega(t)`` and ``R(t)`` accept arrays of times."""

    def __init__(self, inertia, R0, omega0):
        I = np.asarray(inertia, float).reshape(3)
        self.I = I
        self.R0 = np.asarray(R0, float)
        w0 = np.asarray(omega0, float).reshape(3)
        self.w0 = w0
        nw = np.linalg.norm(w0)
        L = I * w0
        self.Lb0 = L
        self.Lw = self.R0 @ L
        # rotation about a principal axis: steady spin
        self.steady = nw == 0 or np.linalg.norm(np.cross(w0, L)) <= 1e-14 * nw * np.linalg.norm(L)
        if self.steady:
            return
        if len(set(np.round(I / I.max(), 14))) < 3:
            raise NotImplementedError("TorqueFreeRotation: axisymmetric bodies are not implemented "
                                      "(only needed for steady spin here)")
        # cyclic relabelling with the intermediate axis in position 1 (0-based)
        mid = int(np.argsort(I)[1])
        perm = [(mid - 1) % 3, mid, (mid + 1) % 3]     # cyclic: det(P) = +1
        self.perm = np.array(perm)
        Ip = I[perm]
        wp = w0[perm]
        T2 = float(np.sum(Ip * wp * wp))               # 2T
        L2 = float(np.sum((Ip * wp) ** 2))             # |L|^2
        self.Lnorm = np.sqrt(L2)
        I1, I2, I3 = Ip
        # precession axis d: the extreme-inertia axis L stays near
        if L2 > T2 * I2:
            d = 0 if I1 > I3 else 2
        else:
            d = 0 if I1 < I3 else 2
        e = 2 - d
        Id, Ie = Ip[d], Ip[e]
        Ad2 = (L2 - T2 * Ie) / (Id * (Id - Ie))
        Ae2 = (L2 - T2 * Id) / (Ie * (Ie - Id))
        A22 = (L2 - T2 * Id) / (I2 * (I2 - Id))
        one_minus_k2 = (L2 - T2 * I2) / (Id * (Id - I2)) / Ad2
        m = 1.0 - one_minus_k2
        if not (0 <= m < 1) or min(Ad2, Ae2, A22) <= 0:
            raise ValueError(f"TorqueFreeRotation: separatrix or invalid data (m = {m})")
        A = np.zeros(3)
        A[d] = np.sign(wp[d]) * np.sqrt(Ad2)
        A[1] = np.sqrt(A22)
        A[e] = np.sign(I3 - I1) * np.sign(A[d]) * np.sqrt(Ae2)
        # Euler's equation for the intermediate axis: I2 A2 lam = (I3 - I1) A1 A3
        lam = (I3 - I1) * A[0] * A[2] / (I2 * A[1])
        if lam <= 0:
            raise AssertionError("TorqueFreeRotation: sign bookkeeping failed")
        phi0 = np.arctan2(wp[1] / A[1], wp[e] / A[e])
        self.s0 = float(ellipf(phi0, m))
        self.m, self.lam, self.A, self.d, self.e = m, lam, A, d, e
        self.inv = np.argsort(perm)
        # fixed body axis never parallel to l_b: the intermediate principal axis
        self.a = np.eye(3)[mid]
        # P from R(0) = P A(0)
        self.P = self.R0 @ self._frame(w0[None])[0].T

    # ----------------------------------------------------------------- angular velocity
    def omega(self, t):
        """Body-fixed angular velocity, shape (nt, 3)."""
        t = np.atleast_1d(np.asarray(t, float))
        if self.steady:
            return np.tile(self.w0, (len(t), 1))
        sn, cn, dn = ellipj(self.lam * t + self.s0, self.m)
        wp = np.zeros((len(t), 3))
        wp[:, self.d] = self.A[self.d] * dn
        wp[:, 1] = self.A[1] * sn
        wp[:, self.e] = self.A[self.e] * cn
        return wp[:, self.inv]

    def omega_dot(self, w):
        """Euler's equations: Theta omega' = (Theta omega) x omega."""
        return np.cross(self.I * w, w) / self.I

    # ----------------------------------------------------------------- orientation
    def _frame(self, w):
        """A(t) (nt, 3, 3): rows b1, b2, b3 = l_b (body coordinates)."""
        lb = self.I * w / self.Lnorm
        n = np.cross(self.a, lb)
        b1 = n / np.linalg.norm(n, axis=1)[:, None]
        b2 = np.cross(lb, b1)
        return np.stack([b1, b2, lb], axis=1)

    def _phidot(self, w):
        lb = self.I * w / self.Lnorm
        lbd = np.cross(lb, w)                     # d l_b / dt in the body frame
        n = np.cross(self.a, lb)
        nn = np.linalg.norm(n, axis=1)
        b1 = n / nn[:, None]
        b2 = np.cross(lb, b1)
        nd = np.cross(self.a, lbd)
        return np.einsum("ni,ni->n", w, lb) + np.einsum("ni,ni->n", nd, b2) / nn

    def precession_angle(self, t, panel=0.005, order=16):
        """phi(t) by composite Gauss-Legendre quadrature of the closed-form phi'
        (vectorised: whole panels of width ``panel`` from 0, plus a partial panel)."""
        t = np.atleast_1d(np.asarray(t, float))
        if np.any(t < 0):
            raise ValueError("times must be >= 0")
        x, wq = _gauss_legendre(order)
        K = max(1, int(np.ceil(t.max() / panel)))
        edges = np.arange(K + 1) * panel
        half = 0.5 * panel
        tt = (edges[:-1, None] + half * (1.0 + x[None, :])).reshape(-1)
        full = half * (self._phidot(self.omega(tt)).reshape(K, order) @ wq)
        cum = np.concatenate([[0.0], np.cumsum(full)])
        k = np.minimum((t // panel).astype(np.int64), K - 1)
        a = edges[k]
        hp = 0.5 * (t - a)
        tp = (a[:, None] + hp[:, None] * (1.0 + x[None, :])).reshape(-1)
        part = hp * (self._phidot(self.omega(tp)).reshape(len(t), order) @ wq)
        return cum[k] + part

    def R(self, t):
        """Rotation matrices (nt, 3, 3), body -> world."""
        t = np.atleast_1d(np.asarray(t, float))
        if self.steady:
            return self.R0 @ _expm_so3(self.w0[None] * t[:, None])
        phi = self.precession_angle(t)
        A = self._frame(self.omega(t))
        c, s = np.cos(phi), np.sin(phi)
        Rz = np.zeros((len(t), 3, 3))
        Rz[:, 0, 0], Rz[:, 0, 1], Rz[:, 1, 0], Rz[:, 1, 1], Rz[:, 2, 2] = c, -s, s, c, 1.0
        return np.einsum("ij,njk,nkl->nil", self.P, Rz, A)


def _expm_so3(x):
    """Rodrigues' formula for each row of ``x`` (n, 3): (n, 3, 3); its Taylor terms below 1e-8 rad."""
    th = np.linalg.norm(x, axis=1)
    K = np.zeros((len(x), 3, 3))
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -x[:, 2], x[:, 1], -x[:, 0]
    K[:, 1, 0], K[:, 2, 0], K[:, 2, 1] = x[:, 2], -x[:, 1], x[:, 0]
    small = th < 1e-8
    ths = np.where(small, 1.0, th)
    a = np.where(small, 1.0, np.sin(ths) / ths)
    b = np.where(small, 0.5, (1 - np.cos(ths)) / ths ** 2)
    return np.eye(3) + a[:, None, None] * K + b[:, None, None] * (K @ K)
