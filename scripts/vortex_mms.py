#!/usr/bin/env python3
"""Body force of the generalized vortex (benchmark vortex_2d), derived with sympy.

Manufactured solution after Kamojjala, Brannon, Sadeghirad and Guilkey, "Verification tests in
solid mechanics", Eng. Comput. 31 (2015): the material of an annulus R_i <= R <= R_o turns
about its centre by the angle alpha(R, t) = g(t) h(R),

    g(t) = A sin(2 pi t / period),
    h(R) = (1 - 4 xi^2)^2,   xi = (R - (R_i + R_o)/2) / (R_o - R_i),

so x(X, t) = Q(alpha) X. h and h' vanish on both radii (R_i = 0.75, R_o = 1.25 gives the
paper's 1 - 32 (R - 1)^2 + 256 (R - 1)^4), so F = I and the traction is zero there: the
annulus needs no boundary condition. The law is mpmlab's plane-strain neo-Hookean
(src/material/materials.hpp; D eq. 2.14):

    sigma = lambda ln(J) / J I + mu / J (F F^T - I),   P = J sigma F^-T,

and the body force per unit mass is b = x_tt - Div_X P / rho0 at the material point X.

This script derives b in Cartesian coordinates from x(X, t) alone (no polar identities), then
checks that it equals the closed form that src/benchmarks/vortex_2d.cpp evaluates, written in
the polar frame (e_r, e_phi) of the current angle phi = Theta + alpha:

    b_r   = R (mu/rho0 alpha_R^2 - alpha_t^2),
    b_phi = R alpha_tt - mu/rho0 (3 alpha_R + R alpha_RR).

(J = 1 for this motion, so lambda drops out.) It prints the closed form and exits 0 when the
two agree at random points and parameters in 40-digit arithmetic, 1 otherwise. The C++ test VortexExact.BodyForceMatchesFiniteDifferences
checks the same closed form by finite differences of x and P.

    /usr/bin/python3 scripts/vortex_mms.py     (python3-sympy; seconds)
"""
import random
import sys

import mpmath
import sympy as sp


def main():
    X, Y, t = sp.symbols("X Y t", real=True)
    lam, mu, rho0 = sp.symbols("lambda mu rho0", positive=True)

    # The motion x = Q(alpha) X with alpha a generic function of (R, t) first: sympy's
    # expressions stay small, and the result holds for any alpha(R, t).
    alpha = sp.Function("alpha")
    R = sp.sqrt(X**2 + Y**2)
    al = alpha(R, t)
    Q = sp.Matrix([[sp.cos(al), -sp.sin(al)], [sp.sin(al), sp.cos(al)]])
    x = Q * sp.Matrix([X, Y])
    F = x.jacobian([X, Y])
    J = sp.trigsimp(sp.expand(F.det()))
    print("det F =", J)
    F_inv = sp.Matrix([[F[1, 1], -F[0, 1]], [-F[1, 0], F[0, 0]]]) / J
    sigma = lam * sp.log(J) / J * sp.eye(2) + mu / J * (F * F.T - sp.eye(2))
    P = J * sigma * F_inv.T
    div_P = sp.Matrix([sp.diff(P[i, 0], X) + sp.diff(P[i, 1], Y) for i in range(2)])
    b = sp.diff(x, t, 2) - div_P / rho0

    # The closed form in the current polar frame, for the same generic alpha.
    Rs = sp.symbols("R", positive=True)
    a = alpha(Rs, t)
    a_R, a_RR = sp.diff(a, Rs), sp.diff(a, Rs, 2)
    b_r = Rs * (mu / rho0 * a_R**2 - sp.diff(a, t) ** 2)
    b_phi = Rs * sp.diff(a, t, 2) - mu / rho0 * (3 * a_R + Rs * a_RR)
    phi = sp.atan2(Y, X) + al
    e_r = sp.Matrix([sp.cos(phi), sp.sin(phi)])
    e_phi = sp.Matrix([-sp.sin(phi), sp.cos(phi)])
    closed = (b_r * e_r + b_phi * e_phi).subs(Rs, R)

    # The vortex's alpha = g(t) h(R) substituted into both.
    A, period, Ri, Ro = sp.symbols("A period R_i R_o", positive=True)
    tt = sp.symbols("tau", positive=True)
    xi = (Rs - (Ri + Ro) / 2) / (Ro - Ri)
    vortex = sp.Lambda((Rs, tt), A * sp.sin(2 * sp.pi * tt / period) * (1 - 4 * xi**2) ** 2)
    b = b.subs(alpha, vortex).doit()
    closed = closed.subs(alpha, vortex).doit()

    # sympy's simplify of the difference takes far too long (Div P of a rotation by a
    # radius-dependent angle is a large expression), so the two exact expressions are evaluated
    # at random points and parameters in 40-digit arithmetic: a difference below 1e-30 of the
    # terms is identity up to the round-off of the evaluation (a wrong coefficient in the closed
    # form shows as a difference of order 1).
    mpmath.mp.dps = 40
    args = (X, Y, t, A, period, Ri, Ro, lam, mu, rho0)
    f_b = sp.lambdify(args, b, "mpmath")
    f_c = sp.lambdify(args, closed, "mpmath")
    rng = random.Random(1)
    worst = 0.0
    for _ in range(40):
        ri, ro = rng.uniform(0.5, 1.0), rng.uniform(1.1, 2.0)
        r, th = mpmath.mpf(rng.uniform(ri, ro)), mpmath.mpf(rng.uniform(-3.1, 3.1))
        vals = [r * mpmath.cos(th), r * mpmath.sin(th)] + [
            mpmath.mpf(v)
            for v in (rng.uniform(0, 2), rng.uniform(0.1, 2), rng.uniform(0.5, 3), ri, ro,
                      rng.uniform(100, 1e4), rng.uniform(100, 1e4), rng.uniform(500, 5000))
        ]
        vb, vc = f_b(*vals), f_c(*vals)
        scale = max(abs(vb[0]), abs(vb[1]), 1)
        worst = max(worst, float(max(abs(vb[0] - vc[0]), abs(vb[1] - vc[1])) / scale))
    ok = J == 1 and worst < 1e-30
    print(f"largest relative difference at 40 random points and parameters: {worst:.3e}")
    print("b_r   =", b_r)
    print("b_phi =", b_phi)
    print("closed form", "agrees" if ok else "DISAGREES", "with b = x_tt - Div P / rho0")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
