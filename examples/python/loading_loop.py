"""A custom loading loop: a soil block compressed by a rigid platen until it fails, then unloaded,
the platen's velocity changed between steps by a rule no configuration key expresses.

The problem is examples/element_block_2d.toml: a 1 m block of Mohr-Coulomb soil (c = 10 kPa,
phi = 30 deg, E = 20 MPa, nu = 0.3) under a confining pressure of 50 kPa, on rollers, compressed
by a smooth platen at 5 mm/s. The loop reads the platen's force after every step (the reaction
on the box of prescribed velocities) and

  1. compresses until the axial strain reaches 1 % (past failure: the stress stays at the
     closed-form strength sigma_1 = N sigma_3 + 2 c sqrt(N) = 184.6 kPa, N = 3);
  2. reverses the platen and unloads until the axial stress is back at the confining pressure.

Unloading is elastic: in plane strain with the lateral stress held, its slope is
E / (1 - nu^2) = 21.98 MPa, and the block keeps a permanent strain. The script checks the
strength and the unloading slope against these closed forms (1 % and 3 %: the platen's force is
the reaction of a damped explicit run, quasi-static to about that) and plots the loop.

    PYTHONPATH=build /usr/bin/python3 examples/python/loading_loop.py --out runs/py_loading_loop
"""
import argparse
import pathlib
import sys

import numpy as np

import mpmlab

ROOT = pathlib.Path(__file__).resolve().parents[2]

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--out", default="runs/py_loading_loop", help="output directory")
args = parser.parse_args()
out = pathlib.Path(args.out)

cfg = mpmlab.Config.from_file(ROOT / "examples" / "element_block_2d.toml")
cfg.set("time.end", 10.0)  # room for both phases; the loop ends the run itself
cfg.set("output.frames", 0)  # frames at the end only
speed = 5.0e-3  # m/s, the example's platen speed
height, width, p0 = 1.0, 1.0, 50.0e3  # m, m, Pa
c, phi, E, nu = 10.0e3, np.radians(30.0), 20.0e6, 0.3
N = (1 + np.sin(phi)) / (1 - np.sin(phi))
strength = N * p0 + 2 * c * np.sqrt(N)

run = mpmlab.Run(cfg, out=out, overwrite=True)
strain, stress = [0.0], [p0]  # axial strain [-], axial stress [Pa] (compression positive)
displacement = 0.0
phase = "loading"
while run.running:
    run.step()
    displacement += (speed if phase == "loading" else -speed) * run.dt
    # The platen's force per metre is the reaction on the prescribed box (negative: it pushes
    # down on the block); with the confining pressure it is the axial stress.
    force = -run.reactions()["reaction_prescribed_y"]
    strain.append(displacement / height)
    stress.append(force / width)
    if phase == "loading" and strain[-1] >= 0.01:
        phase = "unloading"
        run.set_prescribed_velocity([0.0, +speed])  # the platen goes back up
    elif phase == "unloading" and stress[-1] <= p0:
        break
summary = run.finish()  # "interrupted": the loop, not time.end, ended the run

strain, stress = np.array(strain), np.array(stress)
peak = stress.max()
turn = int(np.argmax(strain))
# The unloading slope over its first half (the elastic part away from the turn's transient).
down = slice(turn + 5, turn + (len(strain) - turn) // 2)
slope = np.polyfit(strain[down], stress[down], 1)[0]
permanent = strain[-1]
elastic = E / (1 - nu**2)
print(f"strength {peak / 1e3:.1f} kPa (closed form {strength / 1e3:.1f} kPa)")
print(f"unloading slope {slope / 1e6:.2f} MPa (E / (1 - nu^2) = {elastic / 1e6:.2f} MPa)")
print(f"permanent axial strain {100 * permanent:.3f} % after {run.current_step} steps")

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

fig, ax = plt.subplots(figsize=(5, 4))
ax.plot(100 * strain, stress / 1e3, lw=1)
ax.axhline(strength / 1e3, ls="--", lw=0.8, color="k", label="Mohr-Coulomb strength")
ax.set_xlabel("axial strain [%]")
ax.set_ylabel("axial stress [kPa]")
ax.legend()
fig.tight_layout()
fig.savefig(out / "loading_loop.png", dpi=120)
print(f"plot: {out / 'loading_loop.png'}")

problems = []
if abs(peak / strength - 1) > 0.01:
    problems.append(f"strength {peak:.0f} Pa vs {strength:.0f} Pa")
if abs(slope / elastic - 1) > 0.03:
    problems.append(f"unloading slope {slope:.4g} Pa vs {elastic:.4g} Pa")
if summary["status"] != "interrupted" or not permanent > 0:
    problems.append(f"status {summary['status']}, permanent strain {permanent}")
if problems:
    print("unexpected: " + "; ".join(problems))
    sys.exit(1)
