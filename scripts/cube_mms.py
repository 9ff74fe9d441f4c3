#!/usr/bin/env python3
"""Body force of the vibrating cube (benchmark cube_mms_3d), derived with sympy.

The 3D extension of 001's plate (issue 20): the unit cube [0, L]^3 vibrates along its axes,

    u_i = A sin(2 pi X_i / L) sin(omega t),   omega = c pi / L,   c = sqrt(E / rho0),

with rollers on its six faces (u_i = 0 on X_i = 0 and X_i = L). The law is mpmlab's
compressible neo-Hookean (src/material/materials.hpp; D eq. 2.14):

    sigma = lambda ln(J) / J I + mu / J (F F^T - I),   P = J sigma F^-T,

and the body force per unit mass is b = u_tt - Div_X P / rho0 at the material point X.

This script derives b from u alone with sympy, then checks that it equals the closed form that
src/benchmarks/cube_mms_3d.cpp evaluates (the plate's, 001 eq. 42 with pi^2 u / L^2, in each
direction; F is diagonal, F_ii = 1 + A k cos(k X_i) sin(omega t), k = 2 pi / L):

    b_i = u_i (k^2 / rho0 dP_ii/dF_ii - omega^2),
    dP_ii/dF_ii = (lambda (1 - ln J) + mu) / F_ii^2 + mu,   J = F_11 F_22 F_33.

It prints the closed form and exits 0 when the two agree at random points and parameters in
40-digit arithmetic, 1 otherwise. The C++ test CubeMmsExact.BodyForceMatchesFiniteDifferences
checks the same closed form by finite differences of u and P.

    /usr/bin/python3 scripts/cube_mms.py     (python3-sympy; seconds)
"""
import random
import sys

import mpmath
import sympy as sp


def main():
    Xs = sp.symbols("X1 X2 X3", real=True)
    t = sp.symbols("t", real=True)
    A, L, lam, mu, rho0, c = sp.symbols("A L lambda mu rho0 c", positive=True)
    k, omega = 2 * sp.pi / L, c * sp.pi / L

    u = sp.Matrix([A * sp.sin(k * X) * sp.sin(omega * t) for X in Xs])
    F = sp.eye(3) + u.jacobian(Xs)
    J = F.det()
    sigma = lam * sp.log(J) / J * sp.eye(3) + mu / J * (F * F.T - sp.eye(3))
    P = J * sigma * F.inv().T
    div_P = sp.Matrix([sum(sp.diff(P[i, j], Xs[j]) for j in range(3)) for i in range(3)])
    b = sp.diff(u, t, 2) - div_P / rho0

    # The closed form of src/benchmarks/cube_mms_3d.cpp.
    lnJ = sp.log(F[0, 0] * F[1, 1] * F[2, 2])
    closed = sp.Matrix([
        u[i] * (k**2 / rho0 * ((lam * (1 - lnJ) + mu) / F[i, i] ** 2 + mu) - omega**2)
        for i in range(3)
    ])

    # The two exact expressions evaluated at random points and parameters in 40-digit
    # arithmetic: a difference below 1e-30 of the terms is identity up to the round-off of the
    # evaluation (a wrong coefficient shows as a difference of order 1).
    mpmath.mp.dps = 40
    args = (*Xs, t, A, L, lam, mu, rho0, c)
    f_b = sp.lambdify(args, b, "mpmath")
    f_c = sp.lambdify(args, closed, "mpmath")
    rng = random.Random(1)
    worst = 0.0
    for _ in range(40):
        length = rng.uniform(0.5, 2.0)
        # |A k| < 0.9: J stays positive (the displacement field never inverts the cube).
        amp = rng.uniform(-0.9, 0.9) * length / (2 * float(mpmath.pi))
        vals = [mpmath.mpf(rng.uniform(0, length)) for _ in range(3)] + [
            mpmath.mpf(v)
            for v in (rng.uniform(0, 1), amp, length, rng.uniform(1e3, 1e7), rng.uniform(1e3, 1e7),
                      rng.uniform(500, 5000), rng.uniform(10, 200))
        ]
        vb, vc = f_b(*vals), f_c(*vals)
        scale = max(max(abs(vb[i]) for i in range(3)), 1)
        worst = max(worst, float(max(abs(vb[i] - vc[i]) for i in range(3)) / scale))
    ok = worst < 1e-30
    print(f"largest relative difference at 40 random points and parameters: {worst:.3e}")
    print("b_i = u_i (k^2 / rho0 ((lambda (1 - ln J) + mu) / F_ii^2 + mu) - omega^2)")
    print("closed form", "agrees" if ok else "DISAGREES", "with b = u_tt - Div P / rho0")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
