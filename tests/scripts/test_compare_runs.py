#!/usr/bin/python3
"""scripts/compare_runs.py's comparison to round-off (--rtol): numbers that differ in their last
bits agree, numbers that differ more, other text and integer arrays do not; on synthetic files
of the shapes mpm writes (a CSV frame, summary.json, a binary VTU with raw appended arrays as
io/output.cpp writes them). Exits 1 on the first failed check."""
import importlib.util
import pathlib
import struct
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent.parent
spec = importlib.util.spec_from_file_location("compare_runs", ROOT / "scripts" / "compare_runs.py")
cr = importlib.util.module_from_spec(spec)
spec.loader.exec_module(cr)
cr.RTOL, cr.ATOL = 1e-10, 1e-12

failures = []


def check(name, got_difference, expect_difference, must_name=None):
    ok = (got_difference is not None) == expect_difference
    if ok and must_name is not None and must_name not in got_difference:
        ok = False
    if not ok:
        failures.append(f"{name}: got {got_difference!r}")
    print(f"{'ok  ' if ok else 'FAIL'} {name}: {got_difference}")


def compare(name, a, b):
    return cr.compare_file(pathlib.Path(name), a, b, cr.Agreement())


# A CSV frame: a column's numbers are judged against the column's largest magnitude, so a
# round-off change of a near-zero stress beside large ones agrees.
csv = b"x,y,stress_xy,id\n0.125,0.25,1.5e5,0\n0.375,0.25,2.0e-9,1\n"
check("csv, round-off", compare("p.csv", csv, csv.replace(b"1.5e5", b"150000.00000000003")
                                .replace(b"2.0e-9", b"2.000001e-9")), False)
check("csv, 1e-6 relative", compare("p.csv", csv, csv.replace(b"0.375", b"0.375000375")), True,
      "column x (x)")
# The components of one field share its scale: stress_12, zero by symmetry, may differ at the
# round-off of stress_11; alone in its field it may not.
grouped = b"id,stress_11,stress_12\n0,1.5e5,2.0e-9\n1,1.4e5,-3.0e-9\n"
check("csv, a field's components", compare("p.csv", grouped, grouped.replace(b"2.0e-9",
                                                                            b"2.000001e-9")), False)
alone = b"id,a,b\n0,1.5e5,2.0e-9\n1,1.4e5,-3.0e-9\n"
check("csv, columns of their own", compare("p.csv", alone, alone.replace(b"2.0e-9",
                                                                        b"2.000001e-9")), True,
      "column b")
check("csv, other text", compare("p.csv", csv, csv.replace(b"stress_xy", b"stress_yx")), True)
check("csv, a row more", compare("p.csv", csv, csv + b"1,1,1,2\n"), True)

# summary.json: each number against the pair; round-off quantities (both below atol) agree.
js = b'{"errors": {"stress_rms": 12.5}, "conservation": {"mass": 1e-16}, "status": "ok"}'
check("json, round-off", compare("summary.json", js, js.replace(b"12.5", b"12.500000000000002")
                                 .replace(b"1e-16", b"3.3e-16")), False)
check("json, 1e-3 relative", compare("summary.json", js, js.replace(b"12.5", b"12.5125")), True,
      "errors.stress_rms")
check("json, a string", compare("summary.json", js, js.replace(b'"ok"', b'"failed"')), True)


def vtu(stress, ids):
    """A binary VTU as io/output.cpp writes it: UInt64 byte counts, raw little-endian values."""
    raw = b""
    head = (b'<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="1.0" '
            b'byte_order="LittleEndian" header_type="UInt64">\n  <UnstructuredGrid>\n'
            b'    <FieldData>\n      <DataArray type="Float64" Name="TimeValue" '
            b'NumberOfTuples="1" format="ascii">\n0.001\n      </DataArray>\n    </FieldData>\n'
            b'    <Piece NumberOfPoints="2" NumberOfCells="2">\n      <PointData>\n')
    for kind, name, code, values in (("Int64", "id", "q", ids),
                                     ("Float64", "stress", "d", stress)):
        data = struct.pack(f"<{len(values)}{code}", *values)
        head += (f'        <DataArray type="{kind}" Name="{name}" format="appended" '
                 f'offset="{len(raw)}"/>\n').encode()
        raw += struct.pack("<Q", len(data)) + data
    return (head + b"      </PointData>\n    </Piece>\n  </UnstructuredGrid>\n"
            b'  <AppendedData encoding="raw">\n   _' + raw + b"\n  </AppendedData>\n</VTKFile>\n")


base = vtu([1.5e5, 2.0e-9], [0, 1])
check("vtu, round-off", compare("p.vtu", base, vtu([150000.00000000003, 2.000001e-9], [0, 1])),
      False)
check("vtu, 1e-6 relative", compare("p.vtu", base, vtu([150000.15, 2.0e-9], [0, 1])), True,
      "array stress")
check("vtu, an integer", compare("p.vtu", base, vtu([1.5e5, 2.0e-9], [0, 2])), True,
      "integer array id")
check("vtu, bitwise mode", cr.compare_file(pathlib.Path("p.vtu"), base,
                                           vtu([150000.00000000003, 2.0e-9], [0, 1])), True)

if failures:
    print(f"test_compare_runs: {len(failures)} check(s) failed", file=sys.stderr)
    sys.exit(1)
print("test_compare_runs: every check as it must be")
