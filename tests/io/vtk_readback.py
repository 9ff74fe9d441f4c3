#!/usr/bin/python3
"""Every kind of VTK file mpmlab writes, read by VTK itself (python3-vtk9), the library ParaView
is built on: a file that VTK's XML readers refuse is not an output, whatever meshio or a hand
parser accepts.

For the grid (1D, 2D, 3D; the triangles of a grid's cells and of a mesh file; `mpm mesh --vtu`),
the particle frames (binary and ASCII), the series (.pvd: every file it lists) and the frames of
runs on two processes and on 2 x 2 blocks (.pvtu over its pieces), each file is read with
vtkXMLUnstructuredGridReader (vtkXMLPUnstructuredGridReader for .pvtu), any error VTK reports
fails the check, and the counts of points and cells are compared with what the run says it wrote
(summary.json, the CSV frame);
one value per frame (the stress of the particle of id 1) is compared with the CSV frame.

Usage: vtk_readback.py --mpm build/mpm
"""
import argparse
import csv
import json
import os
import shutil
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

import vtk
from vtk.util.numpy_support import vtk_to_numpy

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
MPIRUN_ENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
              "OMPI_MCA_rmaps_base_oversubscribe": "1", "OMP_NUM_THREADS": "1",
              "OMPI_MCA_btl_vader_single_copy_mechanism": "none",
              "OMPI_MCA_btl": "self,vader", "OMPI_MCA_pml": "ob1"}


class Errors(object):
    """Collects the errors and warnings VTK reports while reading (ErrorEvent, WarningEvent)."""

    def __init__(self):
        self.messages = []

    def __call__(self, obj, event):
        self.messages.append(f"{event}: {obj.GetClassName()}")


def read(path, parallel=False):
    """The unstructured grid VTK reads from path, and the errors it reported."""
    reader = vtk.vtkXMLPUnstructuredGridReader() if parallel else vtk.vtkXMLUnstructuredGridReader()
    errors = Errors()
    reader.AddObserver("ErrorEvent", errors)
    reader.AddObserver("WarningEvent", errors)
    # The readers also report through the global output window: count those too.
    window = vtk.vtkStringOutputWindow()
    vtk.vtkOutputWindow.SetInstance(window)
    reader.SetFileName(path)
    reader.Update()
    text = window.GetOutput()
    if text.strip():
        errors.messages.append(text.strip().splitlines()[0][:300])
    return reader.GetOutput(), errors.messages


def run(cmd, env=None):
    e = dict(os.environ)
    if env:
        e.update(env)
    r = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, env=e, timeout=300)
    if r.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)}: exit {r.returncode}: {r.stderr.strip()[-500:]}")
    return r


def csv_rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def check_frame(path, csv_path, dim, failures, parallel=False, columns=()):
    grid, errors = read(path, parallel)
    what = os.path.basename(path)
    if errors:
        failures.append(f"{what}: VTK reported {errors}")
        return
    rows = csv_rows(csv_path)
    if grid.GetNumberOfPoints() != len(rows) or grid.GetNumberOfCells() != len(rows):
        failures.append(f"{what}: {grid.GetNumberOfPoints()} points and "
                        f"{grid.GetNumberOfCells()} cells, the CSV frame has {len(rows)} rows")
        return
    pd = grid.GetPointData()
    ids = vtk_to_numpy(pd.GetArray("id"))
    stress = vtk_to_numpy(pd.GetArray("stress"))
    names = [pd.GetArray("stress").GetComponentName(k) for k in range(9)]
    if names != ["XX", "XY", "XZ", "YX", "YY", "YZ", "ZX", "ZY", "ZZ"]:
        failures.append(f"{what}: stress components named {names}")
    row = next(r for r in rows if int(r["id"]) == 1)
    k = list(ids).index(1)
    key = "stress_11" if dim > 1 else "stress"
    if key not in row:
        key = "stress_11" if "stress_11" in row else "stress"
    if stress[k][0] != float(row[key]):
        failures.append(f"{what}: stress XX of particle 1 is {stress[k][0]}, the CSV's {row[key]}")
    # Scalar columns (a run of several materials: each particle's "material" and its law's
    # internal variables), every particle's value as in the CSV frame.
    for name in columns:
        array = pd.GetArray(name)
        if array is None:
            failures.append(f"{what}: no point array {name}")
            continue
        values = vtk_to_numpy(array)
        by_id = {int(r["id"]): float(r[name]) for r in rows}
        bad = [int(i) for i, v in zip(ids, values) if v != by_id[int(i)]]
        if bad:
            failures.append(f"{what}: {name} of particle {bad[0]} is not the CSV's")
    print(f"{what}: {grid.GetNumberOfPoints()} points, stress XX of particle 1 = {stress[k][0]:.6g}"
          + (f", columns {', '.join(columns)} as in the CSV" if columns else ""))


def check_grid(path, cells, points, failures, label):
    grid, errors = read(path)
    if errors:
        failures.append(f"{label}: VTK reported {errors}")
        return
    if grid.GetNumberOfCells() != cells or (points is not None and grid.GetNumberOfPoints() != points):
        failures.append(f"{label}: {grid.GetNumberOfCells()} cells and {grid.GetNumberOfPoints()} "
                        f"points, expected {cells} and {points}")
        return
    print(f"{label}: {cells} cells, {grid.GetNumberOfPoints()} points")


def check_pvd(path, failures):
    files = [d.get("file") for d in ET.parse(path).getroot().iter("DataSet")]
    if not files:
        failures.append(f"{path}: lists no data set")
    for f in files:
        full = os.path.join(os.path.dirname(path), f)
        if not os.path.isfile(full):
            failures.append(f"{path} lists {f}, which does not exist")
            continue
        grid, errors = read(full, parallel=f.endswith(".pvtu"))
        if errors or grid.GetNumberOfPoints() == 0:
            failures.append(f"{path} lists {f}: VTK reported {errors}, "
                            f"{grid.GetNumberOfPoints()} points")
    print(f"{os.path.basename(path)}: {len(files)} data sets, each read")


# A body mesh of two parts and two materials (neo-Hookean and tracked_elastic, whose internal
# variables are columns of their own).
TWO_MATERIALS = "tests/data/two_materials_thrown_2d.toml"
MATERIAL_COLUMNS = ("material", "updates", "strain_path")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--mpm", required=True)
    a = ap.parse_args()
    mpm = os.path.abspath(a.mpm)
    failures = []
    tmp = tempfile.mkdtemp(prefix="mpm_vtk_")
    try:
        cases = [
            # (label, config, sets, dim, expected grid cells from the summary's cells)
            ("1D bar", "examples/vibrating_bar_small.toml", ["time.end=3e-7"], 1, 1),
            ("1D bar, ASCII", "examples/vibrating_bar_small.toml",
             ["time.end=3e-7", "output.vtk_format=ascii"], 1, 1),
            ("2D plate", "examples/plate_mms_2d.toml", ["time.end=3e-5"], 2, 1),
            ("3D cube", "examples/cube_mms_3d.toml", ["time.end=2e-4", "grid.cells=3"], 3, 1),
            ("2D triangles of the grid's cells (criss-cross: 4 a cell)",
             "examples/plate_triangles_2d.toml", ["time.end=3e-5"], 2, 4),
            ("2D mesh file", "examples/plate_ps_unstructured_2d.toml", ["time.end=4e-5"], 2, 1),
            ("2D two materials", TWO_MATERIALS, ["time.end=5e-4"], 2, 1),
        ]
        for k, (label, config, sets, dim, per_cell) in enumerate(cases):
            columns = MATERIAL_COLUMNS if config == TWO_MATERIALS else ()
            out = os.path.join(tmp, f"run{k}")
            cmd = [mpm, "run", config, "--quiet", "--out", out, "--set", "output.frames=1"]
            for s in sets:
                cmd += ["--set", s]
            run(cmd)
            summary = json.load(open(os.path.join(out, "summary.json")))
            check_grid(os.path.join(out, "grid.vtu"), per_cell * summary["cells"], None, failures,
                       f"{label}: grid.vtu")
            for frame in ("particles_00000", "particles_00001"):
                check_frame(os.path.join(out, frame + ".vtu"), os.path.join(out, frame + ".csv"),
                            dim, failures, columns=columns)
            check_pvd(os.path.join(out, "particles.pvd"), failures)
        # `mpm mesh --vtu`: the mesh of a Gmsh file, its triangles and vertices.
        out = os.path.join(tmp, "mesh.vtu")
        r = run([mpm, "mesh", "tests/data/meshes/square_v41.msh", "--vtu", out])
        triangles = int(next(l for l in r.stdout.splitlines() if "triangles" in l)
                        .split("triangles")[0].split()[-1])
        check_grid(out, triangles, None, failures, "mpm mesh --vtu")
        # A run on two processes: each frame a .pvtu over one piece per process.
        if shutil.which("mpirun"):
            out = os.path.join(tmp, "mpi")
            run(["mpirun", "-n", "2", "--oversubscribe", mpm, "run", "examples/plate_mms_2d.toml",
                 "--quiet", "--out", out, "--set", "output.frames=1", "--set", "time.end=3e-5"],
                env=MPIRUN_ENV)
            for frame in ("particles_00000", "particles_00001"):
                check_frame(os.path.join(out, frame + ".pvtu"), os.path.join(out, frame + ".csv"),
                            2, failures, parallel=True)
            check_pvd(os.path.join(out, "particles.pvd"), failures)
            # Two materials thrown through the two processes' slabs: each piece's particles
            # with their material and state.
            out = os.path.join(tmp, "mpi_materials")
            run(["mpirun", "-n", "2", "--oversubscribe", mpm, "run", TWO_MATERIALS, "--quiet",
                 "--out", out, "--set", "output.frames=1", "--set", "time.end=5e-3"],
                env=MPIRUN_ENV)
            for frame in ("particles_00000", "particles_00001"):
                check_frame(os.path.join(out, frame + ".pvtu"), os.path.join(out, frame + ".csv"),
                            2, failures, parallel=True, columns=MATERIAL_COLUMNS)
            # The same on 2 x 2 blocks (parallel.blocks): four pieces a frame, the bodies
            # crossing the blocks' boundaries along both axes.
            out = os.path.join(tmp, "mpi_blocks")
            run(["mpirun", "-n", "4", "--oversubscribe", mpm, "run", TWO_MATERIALS, "--quiet",
                 "--out", out, "--set", "output.frames=1", "--set", "time.end=5e-3",
                 "--set", 'parallel.blocks="2x2"'], env=MPIRUN_ENV)
            for frame in ("particles_00000", "particles_00001"):
                pieces = [f for f in os.listdir(out) if f.startswith(frame + "_p")]
                if len(pieces) != 4:
                    failures.append(f"{frame}.pvtu on 2 x 2 blocks: pieces {sorted(pieces)}")
                check_frame(os.path.join(out, frame + ".pvtu"), os.path.join(out, frame + ".csv"),
                            2, failures, parallel=True, columns=MATERIAL_COLUMNS)
        else:
            failures.append("mpirun not found: install openmpi-bin (scripts/deps.sh)")
    except (RuntimeError, subprocess.TimeoutExpired, StopIteration, OSError, KeyError) as e:
        failures.append(f"{type(e).__name__}: {e}")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    for f in failures:
        print("FAILED:", f)
    print("VTK read-back: " + ("FAILED" if failures else "every file read by VTK"))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
