"""The Python module against the command line: the same bytes, the same messages, the same
orders; fields, errors, checkpoints and a changed boundary condition.

Run by ctest (Python.Module) with PYTHONPATH=build and MPM_BINARY=build/mpm:
    PYTHONPATH=build MPM_BINARY=build/mpm /usr/bin/python3 -m pytest -q tests/python
"""
import csv
import json
import os
import pathlib
import subprocess

import numpy as np
import pytest

import mpmlab

ROOT = pathlib.Path(__file__).resolve().parents[2]
MPM = os.environ.get("MPM_BINARY", str(ROOT / "build" / "mpm"))
EXAMPLES = ROOT / "examples"
# summary.json's fields that measure the machine, not the run.
TIMING = {"wall_seconds", "ns_per_particle_step", "first_step_seconds", "sort_seconds",
          "peak_memory_bytes", "steps_per_second"}


def mpm(*args, check=True):
    r = subprocess.run([MPM, *map(str, args)], capture_output=True, text=True)
    if check and r.returncode != 0:
        raise AssertionError(f"mpm {' '.join(map(str, args))}: {r.returncode}\n{r.stderr}")
    return r


def without_timing(obj):
    if isinstance(obj, dict):
        return {k: without_timing(v) for k, v in obj.items() if k not in TIMING}
    if isinstance(obj, list):
        return [without_timing(v) for v in obj]
    return obj


def assert_same_outputs(a, b):
    # (.mpm.lock holds the pid of the process that ran.)
    names_a = sorted(p.name for p in a.iterdir() if p.name != ".mpm.lock")
    names_b = sorted(p.name for p in b.iterdir() if p.name != ".mpm.lock")
    assert names_a == names_b
    for name in names_a:
        if name == "summary.json":
            sa = json.loads((a / name).read_text())
            sb = json.loads((b / name).read_text())
            assert without_timing(sa) == without_timing(sb)
        else:
            assert (a / name).read_bytes() == (b / name).read_bytes(), name


# A short vibrating bar (1D) and a coarse 2D plate: each runs in well under a second.
CASES = {
    "mms_1d": (EXAMPLES / "mms_1d.toml", ["time.end=0.004"]),
    "plate_mms_2d": (EXAMPLES / "plate_mms_2d.toml", ["grid.cells=8"]),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_run_writes_the_bytes_of_mpm_run(case, tmp_path):
    config, sets = CASES[case]
    cli = tmp_path / "cli"
    mpm("run", config, "--out", cli, "--quiet", *[a for s in sets for a in ("--set", s)])
    cfg = mpmlab.Config.from_file(config, sets)
    whole = mpmlab.Run(cfg, out=tmp_path / "py").run()
    assert whole["status"] == "ok"
    assert_same_outputs(cli, tmp_path / "py")
    # Taken in pieces, looked at between them: the same bytes again.
    run = mpmlab.Run(cfg, out=tmp_path / "pieces")
    run.step()
    run.particles()
    run.advance(0.5 * run.end_time)
    assert run.time >= 0.5 * run.end_time - 1e-12 and run.current_step < run.total_steps
    run.grid()
    run.step(3)
    run.run()
    assert_same_outputs(cli, tmp_path / "pieces")
    # A finished run lets go of its directory: the next run into it (overwrite) is not refused,
    # while a running one holds it.
    again = mpmlab.Run(cfg, out=tmp_path / "pieces", overwrite=True)
    with pytest.raises(mpmlab.InputError, match="pid"):
        mpmlab.Run(cfg, out=tmp_path / "pieces", overwrite=True)
    again.run()


def test_set_validates_as_the_command_line(tmp_path):
    cfg = mpmlab.Config.from_file(EXAMPLES / "mms_1d.toml")
    with pytest.raises(mpmlab.InputError) as py_error:
        cfg.set("grid.cells", 0)
    assert py_error.value.exit_code == 2
    cli = mpm("run", EXAMPLES / "mms_1d.toml", "--set", "grid.cells=0", "--out", tmp_path / "x",
              check=False)
    assert cli.returncode == 2
    # The same message after the origin (the command line's "--set grid.cells=0", the call here).
    py_message = str(py_error.value)
    assert py_message.startswith("Config.set('grid.cells', 0)")
    tail = py_message[len("Config.set('grid.cells', 0)"):]
    assert tail.strip() and tail in cli.stderr
    # Unchanged after the refusal; an unknown key names the right one.
    assert cfg.get("grid.cells") == 16
    with pytest.raises(mpmlab.InputError, match="grid.cells"):
        cfg.set("grid.cellz", 3)
    with pytest.raises(mpmlab.InputError, match="method.basis"):
        cfg.set("method.basis", "cubic")
    cfg["grid.cells"] = 32
    assert cfg["grid.cells"] == 32 and cfg.where("grid.cells") == "Config.set('grid.cells', 32)"
    with pytest.raises(mpmlab.InputError):
        mpmlab.Config.from_file(tmp_path / "missing.toml")


def test_from_dict_equals_the_file():
    text = (EXAMPLES / "mms_1d.toml").read_text()
    import tomllib
    d = tomllib.loads(text)
    a = mpmlab.Config.from_dict(d)
    b = mpmlab.Config.from_file(EXAMPLES / "mms_1d.toml")
    for key in ("grid.cells", "time.dt", "time.end", "material.youngs_modulus", "method.basis"):
        assert a[key] == b[key]
    # Messages name the dict's entry, also those of a run made from it.
    d["grid"]["cells"] = 0
    with pytest.raises(mpmlab.InputError, match=r"^dict\['grid'\]\['cells'\]: .*out of range"):
        mpmlab.Config.from_dict(d)
    d["grid"]["cells"] = 16
    d["time"]["dt"] = 1e-2
    with pytest.raises(mpmlab.InputError, match=r"^dict\['time'\]\['dt'\]: .*stability limit"):
        mpmlab.Run(mpmlab.Config.from_dict(d))


def test_keys_and_methods_are_the_command_lines():
    keys = {k["name"]: k for k in mpmlab.keys()}
    assert keys["grid.cells"]["type"] == "integer" or keys["grid.cells"]["type"].startswith("int")
    cli_keys = mpm("keys").stdout
    for name in keys:
        assert name in cli_keys
    methods = mpmlab.methods()
    listed = mpm("list").stdout
    for section, entries in methods.items():
        assert entries, section
        for e in entries:
            assert e["name"] in listed
    assert "linear" in [b["name"] for b in methods["bases"]]


def test_fields_are_copies_and_match_the_frame(tmp_path):
    cfg = mpmlab.Config.from_file(EXAMPLES / "plate_mms_2d.toml", ["grid.cells=8",
                                                                    "output.vtk=false"])
    run = mpmlab.Run(cfg, out=tmp_path / "r")
    run.run()
    p = run.particles()
    n = len(p["id"])
    assert p["x"].shape == (n, 2) and p["stress"].shape == (n, 2, 2) and p["F"].shape == (n, 2, 2)
    # The last CSV frame holds the same values (17 significant digits: the same doubles).
    frames = sorted((tmp_path / "r").glob("particles_*.csv"))
    with open(frames[-1]) as f:
        rows = {int(r["id"]): r for r in csv.DictReader(f)}
    for i in range(n):
        r = rows[int(p["id"][i])]
        assert float(r["x_1"]) == p["x"][i, 0] and float(r["x_2"]) == p["x"][i, 1]
        assert float(r["stress_12"]) == p["stress"][i, 0, 1]
    # A copy: changing it changes nothing in the run.
    p["x"][:] = 0.0
    assert np.array_equal(run.particles()["id"], p["id"])
    assert not np.any(run.positions == 0.0)
    # The grid's mass is the particles' (lumped sums conserve it to round-off).
    g = run.grid()
    assert g["x"].shape == (len(g["mass"]), 2)
    assert g["mass"].sum() == pytest.approx(p["mass"].sum(), rel=1e-12)
    # history() is history.csv, value for value.
    h = run.history()
    with open(tmp_path / "r" / "history.csv") as f:
        table = list(csv.DictReader(f))
    assert len(h["time"]) == len(table)
    for name in h:
        assert [float(r[name]) for r in table] == list(h[name])


def test_history_without_an_output_directory():
    cfg = mpmlab.Config.from_file(EXAMPLES / "mms_1d.toml", ["time.end=0.002"])
    run = mpmlab.Run(cfg)
    summary = run.run()
    h = run.history()
    assert h["time"][0] == 0.0 and h["time"][-1] == pytest.approx(0.002)
    assert summary["status"] == "ok" and summary["errors"]["stress_rel_l2"] > 0
    with pytest.raises(mpmlab.InputError, match="output directory"):
        mpmlab.Run(cfg).checkpoint()


def test_a_failure_raises_its_class_and_keeps_the_outputs(tmp_path):
    # A plate thrown upwards out of its grid: exit code 4 (a particle left the grid).
    config = EXAMPLES / "custom_plate_2d.toml"
    sets = ['initial.velocity=["0", "5"]', "time.end=0.05"]
    cli = mpm("run", config, "--out", tmp_path / "cli", "--quiet",
              *[a for s in sets for a in ("--set", s)], check=False)
    assert cli.returncode == 4
    run = mpmlab.Run(mpmlab.Config.from_file(config, sets), out=tmp_path / "py")
    with pytest.raises(mpmlab.LeftGridError) as e:
        run.run()
    assert isinstance(e.value, mpmlab.RunFailed) and e.value.exit_code == 4
    assert "left the grid" in str(e.value) and str(e.value) in cli.stderr
    # Finished: summary.json says failed, the failing state is the last frame, as on the CLI.
    assert run.finished and run.summary["status"] == "failed"
    assert run.current_step < run.total_steps
    assert_same_outputs(tmp_path / "cli", tmp_path / "py")


def test_checkpoint_and_restart_continue_bit_for_bit(tmp_path):
    cfg = mpmlab.Config.from_file(EXAMPLES / "mms_1d.toml", ["time.end=0.004"])
    whole = mpmlab.Run(cfg, out=tmp_path / "whole")
    whole.run()
    first = mpmlab.Run(cfg, out=tmp_path / "first")
    first.step(150)
    first.checkpoint()
    stopped = first.finish()
    assert stopped["status"] == "interrupted"
    again = mpmlab.Run.restart(tmp_path / "first" / "checkpoint.bin")
    assert again.current_step == 150
    again.run()
    a, b = whole.particles(), again.particles()
    order_a, order_b = np.argsort(a["id"]), np.argsort(b["id"])
    for name in ("x", "v", "stress", "F"):
        assert np.array_equal(a[name][order_a], b[name][order_b]), name
    with pytest.raises(mpmlab.InputError, match="time.end"):
        mpmlab.Run.restart(tmp_path / "first" / "checkpoint.bin", overrides=["grid.cells=8"])


def test_study_orders_are_the_command_lines(tmp_path):
    refine = "grid.cells=8,16,32"
    mpm("study", EXAMPLES / "mms_1d.toml", "--refine", refine, "--set", "time.end=0.004",
        "--methods", "linear/direct,bspline2/direct", "--out", tmp_path / "cli")
    cfg = mpmlab.Config.from_file(EXAMPLES / "mms_1d.toml", ["time.end=0.004"])
    rows = mpmlab.study(cfg, {"grid.cells": [8, 16, 32]},
                        methods=["linear/direct", "bspline2/direct"], frame=False)
    with open(tmp_path / "cli" / "study.csv") as f:
        cli_rows = list(csv.DictReader(f))
    assert len(rows) == len(cli_rows) == 6
    for r, c in zip(rows, cli_rows):
        assert r["method"] == c["method"] and r["status"] == c["status"] == "ok"
        assert r["stress_rel_l2"] == float(c["stress_rel_l2"])
    # The orders study.txt prints, to its two decimals.
    table = (tmp_path / "cli" / "study.txt").read_text()
    for r in rows:
        if r["order_stress_rms"] is not None:
            assert f"{r['order_stress_rms']:.2f}" in table
    assert rows[1]["order_stress_rms"] == pytest.approx(
        np.log(rows[0]["stress_rms"] / rows[1]["stress_rms"]) / np.log(rows[0]["h"] / rows[1]["h"]))


def test_finishing_early_is_not_ok(tmp_path):
    cfg = mpmlab.Config.from_file(EXAMPLES / "mms_1d.toml", ["time.end=0.004"])
    run = mpmlab.Run(cfg, out=tmp_path / "r")
    run.step(10)
    summary = run.finish()
    assert summary["status"] == "interrupted" and run.finished
    with pytest.raises(mpmlab.InputError, match="finished"):
        run.step()
    with pytest.raises(mpmlab.InputError, match="finished"):
        run.checkpoint()


def test_internal_variables_are_the_frames(tmp_path):
    # Mohr-Coulomb carries its plastic strain, yield mode and out-of-plane stress; the CSV frame
    # holds the same columns.
    cfg = mpmlab.Config.from_file(EXAMPLES / "element_block_2d.toml",
                                  ["output.vtk=false", "time.end=2.0"])
    run = mpmlab.Run(cfg, out=tmp_path / "r", threads=2)
    run.run()
    p = run.particles()
    assert set(p["internal"]) == {"plastic_strain", "yield_mode", "stress_zz"}
    assert p["internal"]["plastic_strain"].max() > 0
    frames = sorted((tmp_path / "r").glob("particles_*.csv"))
    with open(frames[-1]) as f:
        rows = {int(r["id"]): r for r in csv.DictReader(f)}
    for name, values in p["internal"].items():
        assert [float(rows[int(i)][name]) for i in p["id"]] == list(values)


def test_changing_the_prescribed_velocity_between_steps(tmp_path):
    cfg = mpmlab.Config.from_file(EXAMPLES / "element_block_2d.toml", ["time.end=0.05"])
    run = mpmlab.Run(cfg)
    run.step(10)
    g = run.grid()
    top = np.isclose(g["x"][:, 1], 1.0) & (g["x"][:, 0] <= 1.0 + 1e-12)
    assert np.all(g["velocity"][top, 1] == -5e-3)
    run.set_prescribed_velocity([0.0, 2e-3])
    run.step()
    g = run.grid()
    assert np.all(g["velocity"][top, 1] == 2e-3)
    with pytest.raises(mpmlab.InputError, match="components"):
        run.set_prescribed_velocity([1.0])
    with pytest.raises(mpmlab.InputError, match="prescribed"):
        mpmlab.Run(mpmlab.Config.from_file(EXAMPLES / "mms_1d.toml")).set_prescribed_velocity([0])


def test_reconstruct_on_arrays_is_the_command_lines():
    # D 5.2.3's playground: sin(x) + 2 on 4 elements of [0, 4 pi], 3 uniform points a element.
    a, b, cells = 0.0, 4 * np.pi, 4
    h = (b - a) / cells
    x = np.array([a + (e + (k + 0.5) / 3) * h for e in range(cells) for k in range(3)])
    f = np.sin(x) + 2
    # The RMS error over 100 Gauss points per element, as `mpm reconstruct` prints it.
    xi, _ = np.polynomial.legendre.leggauss(100)
    at = np.concatenate([a + (e + 0.5) * h + 0.5 * h * xi for e in range(cells)])
    for mapping in ("tls", "cubic_spline", "mls", "imls"):
        kw = {}
        if mapping == "tls":
            # The conservative fit keeps the exact element integrals (D eq. 5.9).
            kw["element_integrals"] = [np.cos(a + e * h) - np.cos(a + (e + 1) * h) + 2 * h
                                       for e in range(cells)]
        values = mpmlab.reconstruct(x, f, a, b, cells, at, mapping=mapping, **kw)
        rms = np.sqrt(np.mean((values - (np.sin(at) + 2)) ** 2))
        cli = mpm("reconstruct", "--function", "sin(x)+2", "--upper", "4*pi", "--cells", cells,
                  "--mapping", mapping, "--points", "uniform:3", "--error-points", 100).stdout
        line = next(ln for ln in cli.splitlines() if ln.startswith("RMS error"))
        assert f"{rms:.6e}" == line.split()[-1], mapping
    # TLS with three terms reproduces a quadratic to round-off, and refuses a point outside.
    q = 1 + x - 0.3 * x**2
    values = mpmlab.reconstruct(x, q, a, b, cells, at)
    assert np.max(np.abs(values - (1 + at - 0.3 * at**2))) < 1e-10
    with pytest.raises(mpmlab.InputError, match="outside"):
        mpmlab.reconstruct(x, f, a, b, cells, [b + 1])


def test_reconstruct_in_2d_is_the_command_lines():
    # D 6.2.1: sin(x) cos(y) on 5 x 5 elements of [0, 5]^2, 2 x 3 inner points a element, six
    # Taylor terms; the RMS error over 2 x 2 Gauss points a element is 6.17e-3 (the README's).
    cells, h = 5, 1.0
    pts = np.array([((i + kx / 3) * h, (j + ky / 4) * h) for j in range(cells)
                    for i in range(cells) for ky in (1, 2, 3) for kx in (1, 2)])
    f = np.sin(pts[:, 0]) * np.cos(pts[:, 1])
    g = np.polynomial.legendre.leggauss(2)[0]
    at = np.array([((i + 0.5 + 0.5 * gx) * h, (j + 0.5 + 0.5 * gy) * h) for j in range(cells)
                   for i in range(cells) for gy in g for gx in g])
    # The exact element integrals (separable): int sin x dx * int cos y dy per element.
    integrals = [(np.cos(i * h) - np.cos((i + 1) * h)) * (np.sin((j + 1) * h) - np.sin(j * h))
                 for j in range(cells) for i in range(cells)]
    values = mpmlab.reconstruct(pts, f, 0.0, 5.0, cells, at, terms=6,
                                element_integrals=integrals)
    rms = np.sqrt(np.mean((values - np.sin(at[:, 0]) * np.cos(at[:, 1])) ** 2))
    cli = mpm("reconstruct", "--dim", 2, "--function", "sin(x)*cos(y)", "--upper", 5, "--cells",
              cells, "--terms", 6, "--points", "inner:2x3", "--error-points", 2).stdout
    line = next(ln for ln in cli.splitlines() if ln.startswith("RMS error"))
    assert f"{rms:.6e}" == line.split()[-1] == "6.170989e-03"
    with pytest.raises(mpmlab.InputError, match="one-dimensional"):
        mpmlab.reconstruct(pts, f, 0.0, 5.0, cells, at, mapping="mls")


def test_spline_mass_on_arrays():
    import scipy.sparse

    # The 1D matrix of exact Gauss quadrature has the condition number `mpm massmatrix` prints.
    p, cells = 2, 8
    g, w = np.polynomial.legendre.leggauss(p + 1)
    h = 1.0 / cells
    x = np.concatenate([(e + 0.5) * h + 0.5 * h * g for e in range(cells)])
    wts = np.tile(0.5 * h * w, cells)
    M = mpmlab.spline_mass(x[:, None], wts, 0.0, 1.0, cells, p)
    assert scipy.sparse.issparse(M) and M.shape == (cells + p, cells + p)
    # Partition of unity: the entries sum to the weights' sum, and each row to int phi_i.
    assert M.sum() == pytest.approx(1.0, rel=1e-14)
    eig = np.linalg.eigvalsh(M.toarray())
    row = mpmlab.massmatrix(dim=1, degrees=[p], cells=[cells], boundary="free")[0]
    assert eig.max() / eig.min() == pytest.approx(row["kappa"], rel=1e-9)
    # The values: points by functions, rows summing to one (2D, tensor product).
    pts = np.random.default_rng(1).uniform(0.0, 1.0, size=(50, 2))
    V = mpmlab.spline_values(pts, [0, 0], [1, 1], [4, 4], 3)
    assert V.shape == (50, 7 * 7)
    assert np.allclose(np.asarray(V.sum(axis=1)).ravel(), 1.0, rtol=0, atol=1e-14)


def test_massmatrix_is_the_command_lines(tmp_path):
    mpm("massmatrix", "--dim", 2, "--degrees", 1, 2, "--cells", 8, 16, "--csv", tmp_path / "m.csv")
    with open(tmp_path / "m.csv") as f:
        cli = list(csv.DictReader(f))
    rows = mpmlab.massmatrix(dim=2, degrees=[1, 2], cells=[8, 16])
    assert len(rows) == len(cli) == 4
    for r, c in zip(rows, cli):
        assert (r["degree"], r["cells"]) == (int(c["degree"]), int(c["cells"]))
        assert r["kappa"] == float(c["kappa"])
        assert r["cg_iterations"] == int(c["cg_iterations"])
        assert r["pmg_cycles"] == int(c["pmg_cycles"])
    assert rows[2]["kappa_published"] == 52.1  # 004 Table 4.2, p = 2, h^-1 = 8
