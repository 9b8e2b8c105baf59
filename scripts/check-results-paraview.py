"""Opens a peritwin results XDMF with ParaView's DEFAULT reader and checks what a user sees.

Run with pvbatch (ParaView 5.11, Debian 12 packages paraview + python3-paraview):

    pvbatch scripts/check-results-paraview.py out/results/b1-ct/b1-ct.xdmf

OpenDataFile picks the reader ParaView's GUI picks for a .xdmf (Xdmf3ReaderS/T, which crashed
with SIGSEGV in vtkXdmf3DataSet::CopyShape on the X_Y geometry of results layout 2). The script
lists the time steps and the point arrays, reads the last step, and checks: the reader is an
Xdmf3 reader; every step has the node count of the mesh; damage (1 component, in [0, 1]),
displacement (3, z = 0, not all zero), strain (6: Tensor6), dilatation and max_principal_strain
(1) are there; and at every step every array equals, value for value, what the legacy XDMFReader
(an independent reader of the same files) reads (its strain expanded to 9 components). Exit 0 when all hold, 1 otherwise.
"""
import math
import sys

from paraview import servermanager
from paraview.simple import OpenDataFile, XDMFReader

EXPECTED = {"damage": 1, "displacement": 3, "strain": 6, "dilatation": 1,
            "max_principal_strain": 1}


def fetch(reader, time):
    # The proxy's own UpdatePipeline: paraview.simple.UpdatePipeline(time=0.0) ignores a time of
    # 0 (it tests `if time:`) and then serves whatever step was updated last.
    reader.UpdatePipeline(time)
    return servermanager.Fetch(reader)


def components6(data, name):
    """A symmetric tensor as Tensor6 (xx, xy, xz, yy, yz, zz): the legacy reader expands it to 9."""
    a = data.GetPointData().GetArray(name)
    if a.GetNumberOfComponents() != 9:
        return values(data, name)
    return [a.GetComponent(i, c) for i in range(a.GetNumberOfTuples()) for c in (0, 1, 2, 4, 5, 8)]


def values(data, name):
    a = data.GetPointData().GetArray(name)
    return [a.GetComponent(i, c) for i in range(a.GetNumberOfTuples())
            for c in range(a.GetNumberOfComponents())]


def main(path):
    failures = []
    reader = OpenDataFile(path)
    kind = reader.GetXMLName()
    times = list(reader.TimestepValues)
    print(f"reader: {kind}")
    print(f"time steps (cycles): {len(times)}: {times}")
    if not kind.startswith("Xdmf3Reader"):
        failures.append(f"the default reader is {kind}, not Xdmf3ReaderS/T")
    if not times:
        failures.append("no time steps")
        times = [0.0]
    data = fetch(reader, times[-1])
    points = data.GetNumberOfPoints()
    arrays = {data.GetPointData().GetArrayName(i):
              data.GetPointData().GetArray(i).GetNumberOfComponents()
              for i in range(data.GetPointData().GetNumberOfArrays())}
    print(f"last step: {points} points, point arrays {arrays}")
    for name, components in EXPECTED.items():
        if arrays.get(name) != components:
            failures.append(f"array {name}: {arrays.get(name)} components, expected {components}")
    if "damage" in arrays:
        d = values(data, "damage")
        print(f"damage: min {min(d):.4f} max {max(d):.4f}")
        if min(d) < 0.0 or max(d) > 1.0:
            failures.append("damage outside [0, 1]")
    if "displacement" in arrays:
        u = values(data, "displacement")
        largest = max(math.hypot(u[3 * k], u[3 * k + 1]) for k in range(points))
        print(f"displacement: largest |u| {largest:.6e} m")
        if not largest > 0.0 or any(u[3 * k + 2] != 0.0 for k in range(points)):
            failures.append("displacement all zero or with a z component")
    if "max_principal_strain" in arrays:
        e = [v for v in values(data, "max_principal_strain") if math.isfinite(v)]
        print(f"max principal strain: largest {max(e):.6e}")
    # Every step against the legacy reader.
    legacy = XDMFReader(FileNames=[path])
    if list(legacy.TimestepValues) != list(reader.TimestepValues):
        failures.append("the legacy reader lists other time steps")
    for time in times:
        a = fetch(reader, time)
        b = fetch(legacy, time)
        if a.GetNumberOfPoints() != points:
            failures.append(f"step {time}: {a.GetNumberOfPoints()} points")
        for name in EXPECTED:
            if a.GetPointData().GetArray(name) is None:
                continue
            if components6(a, name) != components6(b, name):
                failures.append(f"step {time}: {name} differs from the legacy reader's")
    for f in failures:
        print(f"FAIL: {f}")
    print("ok" if not failures else f"{len(failures)} failures")
    return 0 if not failures else 1


if __name__ == "__main__":
    if len(sys.argv) != 2:
        print("usage: pvbatch check-results-paraview.py RESULTS.xdmf", file=sys.stderr)
        sys.exit(2)
    sys.exit(main(sys.argv[1]))
