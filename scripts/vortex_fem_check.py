#!/usr/bin/env python3
"""Second implementation for the generalized vortex (benchmark vortex_2d): a total-Lagrangian
finite-element solution of the same manufactured problem, without particles, grid crossing or
mappings, to tell whether the exact solution is dynamically stable over the benchmark's run.

Written after the plate of 001 (scripts/plate_fem_check.py; docs/verification.md, "The exact
solution at A = 0.1 m is unstable"), where a plain FEM started from the exact state departs from
it exponentially because the manufactured solution's own perturbations grow. The same two
questions for the vortex: does a consistent FEM started from the exact state converge to it at
its order at T (then the exact solution is stable over the run, as far as the discretisation's
own errors can tell), and how much does the FEM of the equation linearised about the exact
solution amplify a perturbation over [0, T]?

Problem (examples/vortex_2d.toml, scripts/vortex_mms.py): the annulus 0.75 m <= R <= 1.25 m
turns about the origin by alpha(R, t) = g(t) h(R), g = A sin(2 pi t / period), period = 2 s,
h = (1 - 4 xi^2)^2, xi = (R - 1) / 0.5, so x = Q(alpha) X, F = Q(alpha) (I + g h'(R) / R
W X X^T) with W the rotation by pi/2, J = 1. Plane-strain neo-Hookean
P = mu (F - F^-T) + lambda ln(J) F^-T, E = 1000 Pa, nu = 0.3, rho0 = 1000 kg/m^3. The body
force b = x_tt - Div_X P / rho0 is evaluated here by central differences of the exact P in X
(x_tt from the motion); --check compares it with the closed form of vortex_mms.py's docstring
(b_r = R (mu/rho0 alpha_R^2 - alpha_t^2), b_phi = R alpha_tt - mu/rho0 (3 alpha_R + R alpha_RR)
in the frame of the current angle Theta + alpha). No boundary condition: both circles are free
(h and h' vanish there, so the exact traction is zero). Initial state: u = 0, v = alpha_t W X.

Discretisation: bilinear quadrilaterals (Q1, straight edges) on a structured polar mesh, n_r
elements across the radius and n_theta = --theta-per-radial x n_r around (12 by default: the
elements are near-square at R = 1, and every refinement halves both sizes), 2 x 2 Gauss points
for the internal force, --body-gauss^2 (3 x 3) for the body force, row-sum lumped mass, central
differences in time (u at whole steps, v at half steps). The body force is evaluated at the
Gauss points of one column of elements and rotated to the others (the field and the mesh are
both equivariant under rotations by 2 pi / n_theta; --check compares with the direct
evaluation). The step is --cfl (0.5) times 2 / omega_max, omega_max the largest frequency of
the tangent problem at t = 0 and at the largest deformation (t = period / 4; power iteration),
unless --dt is given; it scales with the element size, so the time error falls at second order
with the space error.

Output of a run: whether it reaches T (or the time of the first non-finite value or of a
Jacobian <= 0 at a Gauss point), the RMS nodal displacement error at
T/4, T/2, 3T/4 and T, the RMS nodal velocity error at T, and the displacement error at T after
removing the best-fitting rigid motion (translation and rotation, fitted to the nodes): the
body is free and the exact solution's angular momentum is driven by the body force, so an
error in the discrete torque shows as a rigid rotation; the fitted angle is printed. Observed
orders between successive meshes (h halves exactly). An element corner with J <= 0 does not
stop a run (the forces see only the Gauss points) but is reported, with the smallest corner
Jacobian of the nodal interpolant of the exact state over the run: at A = 1 rad that
interpolant itself inverts corners on the coarse meshes (the rotation changes by up to
0.77 rad across one of 4 radial elements), so those meshes cannot represent the solution.

--floquet K: the FEM of the equation linearised about the exact solution,
rho0 w_tt = Div(dP/dF(F_exact(X, t)) [Grad w]) (no body force: it does not depend on w), no
boundary condition, from a random (w, v) at t = 0, propagated over [0, T] K times (power
iteration on the propagator over the run; with T = period this is the Floquet multiplier of
the period). Rigid modes: translations decouple exactly (Grad w = 0); the infinitesimal
rotation of the reference configuration does not (the prescribed body force does not turn with
the body, so a rotated body feels a torque), and at A = 0 it drifts linearly. The growth is
measured in the energy seminorm of the deformation at t = 0 and T, where the exact state is the
reference state: N^2 = (v - Pi v)^T M (v - Pi v) + w^T K0 w, K0 the linear-elastic stiffness at
rest and Pi the M-orthogonal projection onto the three rigid modes (N ignores them); after each
application the rigid parts of w and v are removed before renormalising (the iteration runs on
the deformation subspace). A = 0 is neutral: N is the discrete energy. It also prints what
becomes of a unit rigid angular velocity over [0, T] (A = 0: the angle is omega T, the velocity
stays, no deformation), the part of the rotational mode that the projection removes.

Usage:
    OMP_NUM_THREADS=1 /usr/bin/python3 scripts/vortex_fem_check.py --radial-cells 4 8 16 32
        [--amplitude 0.1 1] [--end 1] [--dt DT | --cfl 0.5] [--theta-per-radial 12]
        [--body-gauss 3] [--check] [--floquet K]
"""

import argparse
import math
import sys
import time

import numpy as np

# The Q1 shape functions of the plate's FEM (the same element; this directory is on sys.path
# when the script runs).
from plate_fem_check import q1  # noqa: E402

RHO0 = 1000.0
E = 1000.0
NU = 0.3
LAM = E * NU / ((1 + NU) * (1 - 2 * NU))
MU = E / (2 * (1 + NU))
R_IN, R_OUT = 0.75, 1.25
R_MID, WIDTH = 0.5 * (R_IN + R_OUT), R_OUT - R_IN
PERIOD = 2.0


# ----------------------------------------------------------------------------- exact solution

def profile(R):
    """h, h', h'' of h(R) = (1 - 4 xi^2)^2, xi = (R - 1) / 0.5 (derivatives in R)."""
    xi = (R - R_MID) / WIDTH
    q = 1 - 4 * xi * xi
    return q * q, -16 * xi * q / WIDTH, (-16 + 192 * xi * xi) / WIDTH**2


def amplitude_t(t, A):
    """g, g', g'' of g(t) = A sin(2 pi t / period)."""
    w = 2 * math.pi / PERIOD
    return A * math.sin(w * t), A * w * math.cos(w * t), -A * w * w * math.sin(w * t)


def exact_x(X, Y, t, A):
    g, _, _ = amplitude_t(t, A)
    al = g * profile(np.hypot(X, Y))[0]
    c, s = np.cos(al), np.sin(al)
    return c * X - s * Y, s * X + c * Y


def exact_v(X, Y, t, A):
    """x_t = alpha_t W x."""
    _, gt, _ = amplitude_t(t, A)
    at = gt * profile(np.hypot(X, Y))[0]
    x, y = exact_x(X, Y, t, A)
    return -at * y, at * x


def exact_a(X, Y, t, A):
    """x_tt = alpha_tt W x - alpha_t^2 x."""
    _, gt, gtt = amplitude_t(t, A)
    h = profile(np.hypot(X, Y))[0]
    at, att = gt * h, gtt * h
    x, y = exact_x(X, Y, t, A)
    return -att * y - at * at * x, att * x - at * at * y


def exact_F(X, Y, t, A):
    """F = Q(alpha) (I + s W X X^T), s = g h'(R) / R, for arrays X, Y: (..., 2, 2)."""
    g, _, _ = amplitude_t(t, A)
    R = np.hypot(X, Y)
    h, hp, _ = profile(R)
    al, s = g * h, g * hp / R
    c, sn = np.cos(al), np.sin(al)
    # G = I + s [[-XY, -Y^2], [X^2, XY]]
    g00, g01, g10, g11 = 1 - s * X * Y, -s * Y * Y, s * X * X, 1 + s * X * Y
    F = np.empty(X.shape + (2, 2))
    F[..., 0, 0] = c * g00 - sn * g10
    F[..., 0, 1] = c * g01 - sn * g11
    F[..., 1, 0] = sn * g00 + c * g10
    F[..., 1, 1] = sn * g01 + c * g11
    return F


def inv_T(F):
    J = F[..., 0, 0] * F[..., 1, 1] - F[..., 0, 1] * F[..., 1, 0]
    G = np.empty_like(F)
    G[..., 0, 0] = F[..., 1, 1] / J
    G[..., 1, 1] = F[..., 0, 0] / J
    G[..., 0, 1] = -F[..., 1, 0] / J
    G[..., 1, 0] = -F[..., 0, 1] / J
    return G, J


def piola(F):
    """P(F) for an array of 2x2 matrices (..., 2, 2); also J."""
    FiT, J = inv_T(F)
    with np.errstate(invalid="ignore", divide="ignore"):
        lnJ = np.log(J)
    return MU * (F - FiT) + lnJ[..., None, None] * LAM * FiT, J


def mm(A, B):
    """A B for arrays of 2x2 matrices, written out (faster than matmul on tiny matrices)."""
    C = np.empty(np.broadcast_shapes(A.shape, B.shape))
    C[..., 0, 0] = A[..., 0, 0] * B[..., 0, 0] + A[..., 0, 1] * B[..., 1, 0]
    C[..., 0, 1] = A[..., 0, 0] * B[..., 0, 1] + A[..., 0, 1] * B[..., 1, 1]
    C[..., 1, 0] = A[..., 1, 0] * B[..., 0, 0] + A[..., 1, 1] * B[..., 1, 0]
    C[..., 1, 1] = A[..., 1, 0] * B[..., 0, 1] + A[..., 1, 1] * B[..., 1, 1]
    return C


def dpiola(F, dF):
    """The directional derivative dP/dF [dF] at F: d(F^-T) = -F^-T dF^T F^-T,
    d(ln J) = tr(F^-1 dF)."""
    FiT, J = inv_T(F)
    dFiT = -mm(mm(FiT, np.swapaxes(dF, -1, -2)), FiT)
    tr = np.einsum("...ji,...ji->...", FiT, dF)  # tr(F^-1 dF) = F^-T : dF
    return MU * (dF - dFiT) + LAM * (tr[..., None, None] * FiT
                                     + np.log(J)[..., None, None] * dFiT)


def body_force(X, Y, t, A, eps=1e-6):
    """b = x_tt - Div P / rho0 with Div P by central differences of the exact P in X."""
    Pxp, _ = piola(exact_F(X + eps, Y, t, A))
    Pxm, _ = piola(exact_F(X - eps, Y, t, A))
    Pyp, _ = piola(exact_F(X, Y + eps, t, A))
    Pym, _ = piola(exact_F(X, Y - eps, t, A))
    ax, ay = exact_a(X, Y, t, A)
    b = np.empty(X.shape + (2,))
    for i, a in ((0, ax), (1, ay)):
        div = (Pxp[..., i, 0] - Pxm[..., i, 0] + Pyp[..., i, 1] - Pym[..., i, 1]) / (2 * eps)
        b[..., i] = a - div / RHO0
    return b


def closed_form_b(X, Y, t, A):
    """vortex_mms.py's closed form (src/benchmarks/vortex_2d.cpp), only for --check."""
    g, gt, gtt = amplitude_t(t, A)
    R = np.hypot(X, Y)
    h, hp, hpp = profile(R)
    aR, aRR, at, att = g * hp, g * hpp, gt * h, gtt * h
    br = R * (MU / RHO0 * aR**2 - at**2)
    bp = R * att - MU / RHO0 * (3 * aR + R * aRR)
    phi = np.arctan2(Y, X) + g * h
    c, s = np.cos(phi), np.sin(phi)
    return np.stack([br * c - bp * s, br * s + bp * c], -1)


# ----------------------------------------------------------------------------- mesh

class Quadrature:
    """Points (xi_g, eta_g) with weights in every element: N (G, 4), dN/dX (E, G, 4, 2),
    weights times det(dX/dxi) (E, G), reference positions X, Y (E, G)."""

    def __init__(self, mesh, points, weights, elements=None):
        el = np.arange(mesh.ne) if elements is None else elements
        Xe = np.stack([mesh.NX[mesh.conn[el]], mesh.NY[mesh.conn[el]]], -1)  # (E, 4, 2)
        N, dref = [], []
        for a, b in points:
            Na, dxi, deta = q1(a, b)
            N.append(Na)
            dref.append(np.stack([dxi, deta], 1))
        self.N, dref = np.array(N), np.array(dref)  # (G, 4), (G, 4, 2)
        jac = np.einsum("ead,gak->egdk", Xe, dref)  # dX_d / dxi_k
        jinv_T, det = inv_T(jac)  # jinv_T[d, k] = dxi_k / dX_d
        self.det = det
        self.dN = np.einsum("gak,egdk->egad", dref, jinv_T)
        self.w = np.asarray(weights)[None, :] * det
        self.X = np.einsum("ga,ea->eg", self.N, Xe[..., 0])
        self.Y = np.einsum("ga,ea->eg", self.N, Xe[..., 1])


def gauss_rule(m):
    g, w = np.polynomial.legendre.leggauss(m)
    pts = [(a, b) for a in g for b in g]
    wts = [wa * wb for wa in w for wb in w]
    return pts, wts


CORNERS = [(-1, -1), (1, -1), (1, 1), (-1, 1)]


class Mesh:
    """nr x nth Q1 elements on the annulus: node (i, j) at radius R_i, angle 2 pi j / nth, index
    i nth + j; element (i, j) between rings i, i + 1 and rays j, j + 1, index i nth + j."""

    def __init__(self, nr, nth):
        self.nr, self.nth = nr, nth
        R = np.linspace(R_IN, R_OUT, nr + 1)
        self.theta = 2 * math.pi * np.arange(nth) / nth
        RR, TT = np.meshgrid(R, self.theta, indexing="ij")
        self.NX, self.NY = (RR * np.cos(TT)).ravel(), (RR * np.sin(TT)).ravel()
        self.nn = self.NX.size
        ii, jj = np.meshgrid(np.arange(nr), np.arange(nth), indexing="ij")
        jp = (jj + 1) % nth
        self.conn = np.stack([ii * nth + jj, (ii + 1) * nth + jj, (ii + 1) * nth + jp,
                              ii * nth + jp], -1).reshape(-1, 4)
        self.ne = self.conn.shape[0]
        self.flat = self.conn.ravel()
        q = Quadrature(self, *gauss_rule(2))
        self.mass = np.bincount(self.flat, (RHO0 * q.N[None] * q.w[..., None]).sum(1).ravel(),
                                minlength=self.nn)
        self.h_radial = WIDTH / nr
        self.h_min = min(self.h_radial, 2 * R_IN * math.sin(math.pi / nth))
        # rigid modes of the reference configuration, M-orthogonal on this symmetric mesh
        one, zero = np.ones(self.nn), np.zeros(self.nn)
        self.rigid = [np.stack([one, zero], 1), np.stack([zero, one], 1),
                      np.stack([-self.NY, self.NX], 1)]

    def assemble(self, fe):
        """Element forces (E, 4, 2) summed into the nodes: (nn, 2)."""
        return np.stack([np.bincount(self.flat, fe[..., d].ravel(), minlength=self.nn)
                         for d in range(2)], 1)

    def rigid_coefficients(self, u):
        m = self.mass[:, None]
        return [np.sum(m * r * u) / np.sum(m * r * r) for r in self.rigid]

    def remove_rigid(self, u):
        out = u.copy()
        for c, r in zip(self.rigid_coefficients(u), self.rigid):
            out -= c * r
        return out


def grad(u, conn, dN):
    """Grad u at the points of a quadrature: (E, G, 2, 2), [d, b] = du_d / dX_b."""
    ue = u[conn]  # (E, 4, 2)
    G = np.empty(dN.shape[:2] + (2, 2))
    for d in range(2):
        for b in range(2):
            G[..., d, b] = np.einsum("ea,ega->eg", ue[..., d], dN[..., b])
    return G


def stress_forces(P, q):
    """-int P Grad N: element forces (E, 4, 2)."""
    wP = P * q.w[..., None, None]
    fe = np.empty((q.dN.shape[0], 4, 2))
    for d in range(2):
        fe[..., d] = -(np.einsum("eg,ega->ea", wP[..., d, 0], q.dN[..., 0])
                       + np.einsum("eg,ega->ea", wP[..., d, 1], q.dN[..., 1]))
    return fe


class BodyForce:
    """Nodal body force rho0 int N b: b by central differences at the Gauss points of column 0,
    the element vectors of column j rotated by 2 pi j / nth."""

    def __init__(self, mesh, m, A):
        self.mesh, self.A = mesh, A
        col0 = np.arange(mesh.nr) * mesh.nth
        self.q = Quadrature(mesh, *gauss_rule(m), elements=col0)
        self.c = np.cos(mesh.theta)[None, :, None]
        self.s = np.sin(mesh.theta)[None, :, None]

    def column0(self, t):
        b = body_force(self.q.X, self.q.Y, t, self.A)  # (nr, G, 2)
        return RHO0 * np.einsum("egd,ga,eg->ead", b, self.q.N, self.q.w)  # (nr, 4, 2)

    def __call__(self, t):
        f0 = self.column0(t)
        fx = self.c * f0[:, None, :, 0] - self.s * f0[:, None, :, 1]  # (nr, nth, 4)
        fy = self.s * f0[:, None, :, 0] + self.c * f0[:, None, :, 1]
        fe = np.stack([fx, fy], -1).reshape(-1, 4, 2)
        return self.mesh.assemble(fe)


# ----------------------------------------------------------------------------- time step

def linear_forces(mesh, q, w, F):
    """Internal force of the linearised problem about F at the points of q: (nn, 2)."""
    return mesh.assemble(stress_forces(dpiola(F, grad(w, mesh.conn, q.dN)), q))


def omega_max(mesh, q, A, times, iters=60, seed=5):
    """Largest frequency of M^-1 K(t), K the tangent stiffness at the exact F(t), over the
    given times (power iteration; the Rayleigh quotient)."""
    rng = np.random.default_rng(seed)
    m = mesh.mass[:, None]
    best = 0.0
    for t in times:
        F = exact_F(q.X, q.Y, t, A)
        x = rng.standard_normal((mesh.nn, 2))
        lam = 0.0
        for _ in range(iters):
            x /= math.sqrt(np.sum(m * x * x))
            Kx = -linear_forces(mesh, q, x, F)
            lam = np.sum(x * Kx)  # x^T K x / x^T M x with x^T M x = 1
            x = Kx / m
        best = max(best, math.sqrt(abs(lam)))
    return best


def choose_dt(mesh, q, A, T, cfl):
    times = [0.0] + ([PERIOD / 4] if T >= PERIOD / 4 else [T])
    w = omega_max(mesh, q, A, times)
    dt_c = 2.0 / w
    steps = int(math.ceil(T / (cfl * dt_c)))
    return T / steps, steps, w


# ----------------------------------------------------------------------------- nonlinear run

def nth_for(nr, per):
    return per * nr


def run(nr, per, A, T, dt, cfl, m_body):
    mesh = Mesh(nr, nth_for(nr, per))
    q = Quadrature(mesh, *gauss_rule(2))
    qc = Quadrature(mesh, CORNERS, [0, 0, 0, 0])
    body = BodyForce(mesh, m_body, A)
    m = mesh.mass[:, None]
    if dt is None:
        dt, steps, wmax = choose_dt(mesh, q, A, T, cfl)
    else:
        steps, wmax = int(round(T / dt)), float("nan")
        dt = T / steps
    X, Y = mesh.NX, mesh.NY

    corner = dict(fem=math.inf, exact=math.inf, first=None)

    def corner_J(u):
        G = grad(u, mesh.conn, qc.dN)
        return float(np.min((1 + G[..., 0, 0]) * (1 + G[..., 1, 1]) - G[..., 0, 1] * G[..., 1, 0]))

    def accel(u, t):
        F = np.eye(2) + grad(u, mesh.conn, q.dN)
        P, J = piola(F)
        if not np.all(J > 0):
            return None, f"Jacobian <= 0 at a Gauss point (min {J.min():.3g})"
        if not np.all(np.isfinite(P)):
            return None, "non-finite stress"
        # an element corner with J <= 0 does not stop the run (the force sees only the Gauss
        # points), but is recorded, with the same for the nodal interpolant of the exact state
        jc = corner_J(u)
        if jc <= 0 and corner["first"] is None:
            corner["first"] = t
        corner["fem"] = min(corner["fem"], jc)
        ex, ey = exact_x(X, Y, t, A)
        corner["exact"] = min(corner["exact"], corner_J(np.stack([ex - X, ey - Y], 1)))
        f = mesh.assemble(stress_forces(P, q)) + body(t)
        return f / m, None

    def errors(u, t):
        ux, uy = exact_x(X, Y, t, A)
        return math.sqrt(np.mean((X + u[:, 0] - ux) ** 2 + (Y + u[:, 1] - uy) ** 2))

    u = np.zeros((mesh.nn, 2))
    v = np.stack(exact_v(X, Y, 0.0, A), 1)
    a, why = accel(u, 0.0)
    vh = v + 0.5 * dt * a
    marks = {int(round(k * steps / 4)): k * T / 4 for k in (1, 2, 3, 4)}
    history = []
    stop = None
    t0 = time.time()
    for s in range(1, steps + 1):
        t = s * dt
        u += dt * vh
        if not np.all(np.isfinite(u)):
            stop, why = t, "non-finite displacement"
            break
        a, why = accel(u, t)
        if a is None:
            stop = t
            break
        vn = vh + 0.5 * dt * a
        if s in marks:
            history.append((marks[s], errors(u, t)))
        vh = vn + 0.5 * dt * a
    out = dict(mesh=mesh, dt=dt, steps=steps, wmax=wmax, stop=stop, why=why,
               history=history, seconds=time.time() - t0, corner=corner)
    if stop is None:
        ex, ey = exact_x(X, Y, T, A)
        vx, vy = exact_v(X, Y, T, A)
        out["u_err"] = errors(u, T)
        out["v_err"] = math.sqrt(np.mean((vn[:, 0] - vx) ** 2 + (vn[:, 1] - vy) ** 2))
        # best rigid motion (Procrustes): x_h ~ Q(theta) (x_e - c_e) + c_h
        xh = np.stack([X + u[:, 0], Y + u[:, 1]], 1)
        xe = np.stack([ex, ey], 1)
        ch, ce = xh.mean(0), xe.mean(0)
        p, r = xe - ce, xh - ch
        th = math.atan2(np.sum(p[:, 0] * r[:, 1] - p[:, 1] * r[:, 0]), np.sum(p * r))
        c, sn = math.cos(th), math.sin(th)
        fit = np.stack([c * p[:, 0] - sn * p[:, 1], sn * p[:, 0] + c * p[:, 1]], 1) + ch
        out["u_err_rigid_removed"] = math.sqrt(np.mean(np.sum((xh - fit) ** 2, 1)))
        out["rigid_angle"] = th
        out["rigid_shift"] = float(np.hypot(*(ch - ce)))
        # scale: RMS exact displacement at the largest deformation (t = period / 4)
        qx, qy = exact_x(X, Y, PERIOD / 4, A)
        out["u_scale"] = math.sqrt(np.mean((qx - X) ** 2 + (qy - Y) ** 2))
    return out


# ----------------------------------------------------------------------------- linearised

def propagate(mesh, q, A, w, v, T, steps, backward=False):
    """Velocity Verlet (central differences) for M w'' = f_lin(w; F_exact(t)) over [0, T]."""
    m = mesh.mass[:, None]
    dt = T / steps
    t = 0.0
    a = linear_forces(mesh, q, w, exact_F(q.X, q.Y, t, A)) / m
    for _ in range(steps):
        v += 0.5 * dt * a
        w += dt * v
        t += dt
        a = linear_forces(mesh, q, w, exact_F(q.X, q.Y, t, A)) / m
        v += 0.5 * dt * a
    return w, v


def seminorm(mesh, q, w, v):
    """Energy seminorm of the deformation at the reference state (rigid modes ignored)."""
    m = mesh.mass[:, None]
    vd = mesh.remove_rigid(v)
    K0w = -linear_forces(mesh, q, w, np.broadcast_to(np.eye(2), q.X.shape + (2, 2)))
    return math.sqrt(np.sum(m * vd * vd) + np.sum(w * K0w))


def floquet(nr, per, A, T, K, dt, cfl, seed=2):
    mesh = Mesh(nr, nth_for(nr, per))
    q = Quadrature(mesh, *gauss_rule(2))
    if dt is None:
        dt, steps, wmax = choose_dt(mesh, q, A, T, cfl)
    else:
        steps, wmax = int(round(T / dt)), float("nan")
        dt = T / steps
    rng = np.random.default_rng(seed)
    w = mesh.remove_rigid(rng.standard_normal((mesh.nn, 2)) * 1e-2)
    v = mesh.remove_rigid(rng.standard_normal((mesh.nn, 2)))
    n0 = seminorm(mesh, q, w, v)
    w /= n0
    v /= n0
    factors = []
    t0 = time.time()
    for _ in range(K):
        w, v = propagate(mesh, q, A, w, v, T, steps)
        g = seminorm(mesh, q, w, v)
        factors.append(g)
        w = mesh.remove_rigid(w) / g
        v = mesh.remove_rigid(v) / g
    # a unit rigid angular velocity (rigid kinetic norm 1)
    r = mesh.rigid[2]
    inertia = np.sum(mesh.mass[:, None] * r * r)
    om0 = 1 / math.sqrt(inertia)
    w, v = propagate(mesh, q, A, np.zeros((mesh.nn, 2)), om0 * r, T, steps)
    rot = dict(angle=mesh.rigid_coefficients(w)[2] / (om0 * T),
               omega=mesh.rigid_coefficients(v)[2] / om0,
               deformation=seminorm(mesh, q, w, v))
    return dict(mesh=mesh, dt=dt, steps=steps, wmax=wmax, factors=factors, rotation=rot,
                seconds=time.time() - t0)


# ----------------------------------------------------------------------------- check

def check(amplitudes):
    rng = np.random.default_rng(0)
    R = rng.uniform(R_IN, R_OUT, 200)
    th = rng.uniform(-math.pi, math.pi, 200)
    X, Y = R * np.cos(th), R * np.sin(th)
    print("| A [rad] | t [s] | max abs(b_fd - b_closed) / max abs(b) | max abs(b) [m/s^2] |")
    print("|---|---|---|---|")
    for A in amplitudes:
        for t in (0.1, 0.37, 0.5, 0.83, 1.3):
            bf, bc = body_force(X, Y, t, A), closed_form_b(X, Y, t, A)
            print(f"| {A:g} | {t:g} | {np.max(np.abs(bf - bc)) / np.max(np.abs(bc)):.2e} | "
                  f"{np.max(np.abs(bc)):.3g} |")
    A, t, eps = max(amplitudes), 0.37, 1e-6
    F = exact_F(X, Y, t, A)
    xp, xm = exact_x(X + eps, Y, t, A), exact_x(X - eps, Y, t, A)
    yp, ym = exact_x(X, Y + eps, t, A), exact_x(X, Y - eps, t, A)
    Ffd = np.empty_like(F)
    for i in range(2):
        Ffd[..., i, 0] = (xp[i] - xm[i]) / (2 * eps)
        Ffd[..., i, 1] = (yp[i] - ym[i]) / (2 * eps)
    print(f"F (A = {A:g}, t = {t}) vs central differences of x: "
          f"{np.max(np.abs(F - Ffd)) / np.max(np.abs(F)):.2e}; largest abs(det F - 1) "
          f"{np.max(np.abs(np.linalg.det(F) - 1)):.2e}")
    e = 1e-4
    a = np.stack(exact_a(X, Y, t, A), -1)
    afd = (np.stack(exact_x(X, Y, t + e, A), -1) - 2 * np.stack(exact_x(X, Y, t, A), -1)
           + np.stack(exact_x(X, Y, t - e, A), -1)) / e**2
    vfd = (np.stack(exact_x(X, Y, t + e, A), -1) - np.stack(exact_x(X, Y, t - e, A), -1)) / (2 * e)
    print(f"x_tt vs central differences in t: {np.max(np.abs(a - afd)) / np.max(np.abs(a)):.2e}; "
          f"x_t: {np.max(np.abs(np.stack(exact_v(X, Y, t, A), -1) - vfd)) / np.max(np.abs(vfd)):.2e}")
    G = np.eye(2) + 0.3 * rng.standard_normal((20, 2, 2))
    dG = rng.standard_normal((20, 2, 2))
    fd = (piola(G + eps * dG)[0] - piola(G - eps * dG)[0]) / (2 * eps)
    print(f"tangent dP/dF vs central differences: "
          f"{np.max(np.abs(fd - dpiola(G, dG))) / np.max(np.abs(fd)):.2e}")
    # traction on the circles: P N = 0 at R_in and R_out
    for Rb in (R_IN, R_OUT):
        Xb, Yb = Rb * np.cos(th), Rb * np.sin(th)
        P, _ = piola(exact_F(Xb, Yb, t, A))
        tr = np.einsum("kij,kj->ki", P, np.stack([Xb, Yb], -1) / Rb)
        print(f"exact traction at R = {Rb}: max abs {np.max(np.abs(tr)):.2e} Pa")
    # the rotated column against the direct evaluation at every Gauss point
    mesh = Mesh(4, 48)
    body = BodyForce(mesh, 3, A)
    q3 = Quadrature(mesh, *gauss_rule(3))
    b = body_force(q3.X, q3.Y, t, A)
    direct = mesh.assemble(RHO0 * np.einsum("egd,ga,eg->ead", b, q3.N, q3.w))
    rot = body(t)
    print(f"nodal body force, column 0 rotated vs direct (4 x 48 mesh): "
          f"{np.max(np.abs(rot - direct)) / np.max(np.abs(direct)):.2e}")
    # the discrete net force and torque of the body force against the exact ones
    f = rot
    net = np.abs(f.sum(0)).max()
    print(f"discrete net body force {net:.2e} N/m (exact 0, by symmetry)")


# ----------------------------------------------------------------------------- main

def order(e1, e2):
    return math.log2(e1 / e2) if e1 and e2 else float("nan")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--radial-cells", type=int, nargs="+", default=[4, 8, 16, 32])
    ap.add_argument("--theta-per-radial", type=int, default=12,
                    help="n_theta = this x n_r (12: near-square elements at R = 1)")
    ap.add_argument("--amplitude", type=float, nargs="+", default=[0.1, 1.0], help="A [rad]")
    ap.add_argument("--end", type=float, default=1.0, help="T [s] (the benchmark's: 1 s)")
    ap.add_argument("--dt", type=float, default=None, help="time step [s] (default: --cfl)")
    ap.add_argument("--cfl", type=float, default=0.5,
                    help="dt = cfl x 2 / omega_max of the tangent problem (default 0.5)")
    ap.add_argument("--body-gauss", type=int, default=3, help="Gauss points a direction, b")
    ap.add_argument("--check", action="store_true",
                    help="compare the finite-difference body force with vortex_mms.py's closed "
                    "form, and the other ingredients with finite differences")
    ap.add_argument("--floquet", type=int, default=0, metavar="K",
                    help="instead of the runs: growth of the linearised problem over [0, T], "
                    "K times (power iteration)")
    args = ap.parse_args()
    if args.check:
        check(args.amplitude)
        return
    per = args.theta_per_radial
    if args.floquet:
        print(f"T = {args.end} s, {args.floquet} applications of the linearised propagator; "
              "energy seminorm of the deformation, rigid modes projected out")
        print("| A [rad] | n_r x n_theta | dt [s] | steps | factors per application | "
              f"geometric mean of the last {args.floquet - args.floquet // 2} | "
              "unit rigid spin at T: angle / (omega T), omega / omega0, deformation | cpu [s] |")
        print("|---|---|---|---|---|---|---|---|")
        for A in args.amplitude:
            for nr in args.radial_cells:
                r = floquet(nr, per, A, args.end, args.floquet, args.dt, args.cfl)
                f = r["factors"]
                tail = f[len(f) // 2:]
                mean = math.exp(sum(math.log(x) for x in tail) / len(tail))
                ro = r["rotation"]
                print(f"| {A:g} | {nr} x {r['mesh'].nth} | {r['dt']:.3e} | {r['steps']} | "
                      + ", ".join(f"{x:.4g}" for x in f) + f" | {mean:.4g} | "
                      f"{ro['angle']:.4g}, {ro['omega']:.4g}, {ro['deformation']:.3g} | "
                      f"{r['seconds']:.0f} |")
                sys.stdout.flush()
        return
    print(f"T = {args.end} s, body force {args.body_gauss}^2 Gauss points, cfl {args.cfl}")
    print("| A [rad] | n_r x n_theta | dt [s] | steps | result | u RMS err at T/4, T/2, 3T/4 | "
          "u RMS err at T [m] | order | v RMS err at T [m/s] | order | u err, rigid removed | "
          "order | fitted angle [rad] | min corner J: FEM (first <= 0), exact interpolant | "
          "cpu [s] |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for A in args.amplitude:
        prev = None
        for nr in args.radial_cells:
            r = run(nr, per, A, args.end, args.dt, args.cfl, args.body_gauss)
            hist = ", ".join(f"{e:.3e}" for _, e in r["history"][:3])
            c = r["corner"]
            cj = (f"{c['fem']:.3g}" + (f" (t = {c['first']:.3f} s)" if c["first"] else "")
                  + f", {c['exact']:.3g}")
            if r["stop"] is not None:
                print(f"| {A:g} | {nr} x {r['mesh'].nth} | {r['dt']:.3e} | {r['steps']} | "
                      f"stops at t = {r['stop']:.4f} s: {r['why']} | {hist} | | | | | | | | {cj} | "
                      f"{r['seconds']:.0f} |")
                prev = None
            else:
                o = [order(prev[k], r[k]) if prev else float("nan")
                     for k in ("u_err", "v_err", "u_err_rigid_removed")]
                print(f"| {A:g} | {nr} x {r['mesh'].nth} | {r['dt']:.3e} | {r['steps']} | "
                      f"reaches T | {hist} | {r['u_err']:.3e} | {o[0]:.2f} | {r['v_err']:.3e} | "
                      f"{o[1]:.2f} | {r['u_err_rigid_removed']:.3e} | {o[2]:.2f} | "
                      f"{r['rigid_angle']:.2e} | {cj} | {r['seconds']:.0f} |")
                prev = r
            sys.stdout.flush()
        if prev is not None:
            print(f"(A = {A:g}: RMS exact displacement at t = period/4 over the nodes of "
                  f"{prev['mesh'].nr} x {prev['mesh'].nth}: {prev['u_scale']:.3e} m)")


if __name__ == "__main__":
    main()
