"""``icosim cosim SCENE --tolerance TOL`` per extrapolation order ``k``: the error at ``t_end`` against the exact
solution and the steps taken, per tolerance, and the stability limit of the fixed macro step beside it.

Two scenes, as tests/problems/fmu/test_tolerance_option.py writes them: ``two`` -- the two-unit scene of fmus/
(two_mass_fd, t_end 0.05 s, first step 1e-4 s; the error of both units' positions and velocities against the rigidly
joined masses); ``om`` -- OMSimulator's DualMassOscillator as Model Exchange (Baumgarte index 1, mu 1e-3, first step
1e-3 s, t_end 1 s; x1's error against DualMassOscillator.mo's exact solution, relative to the amplitude).  For
``om`` the fixed-step runs at ``--fixed`` sizes (t_end 1000 H) say whether the macro step is stable there.

A measurement to quote (docs/benchmarks.md), never an assertion:

    python benchmarks/tolerance.py --scene om --k 1,2 --tolerances 1e-3,1e-4,1e-5,1e-6 [--fixed 2e-3,2.1e-3]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import sys
import tempfile
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "tests"), str(ROOT / "tests" / "problems" / "fmu")]

from test_controlled_scenes import error, scene_file  # noqa: E402
from test_drives import AMPLITUDE, exact  # noqa: E402
from test_drives_outside import BAUMGARTE, om_scene  # noqa: E402
from test_tolerance_option import at_end  # noqa: E402

from icosim.cli import main  # noqa: E402
from icosim.io.netcdf import open_dataset  # noqa: E402
from icosim.problems.fmu.run import run_scene  # noqa: E402


def scene(name, tmp, k):
    if name == "om":
        return om_scene(tmp, "baumgarte", k, 1e-3, 1.0, BAUMGARTE)
    path = scene_file(tmp, "two_mass_fd.yaml", t_end=0.05, H=1e-4)
    data = yaml.safe_load(path.read_text())
    data["coupling"]["k"] = k
    path.write_text(yaml.safe_dump(data))
    return path


def controlled(name, path, tol, out):
    with contextlib.redirect_stdout(io.StringIO()):
        status = main(["cosim", str(path), "--tolerance", repr(tol), "--out", str(out)])
    if status != 0:
        return None
    ds = open_dataset(out)
    if name == "om":
        err = abs(float(ds["position"][0, -1]) - exact([float(ds["time"][-1])])[0, 0]) / AMPLITUDE
    else:
        err = error(at_end(path, ds))
    return err, int(ds.attrs["control_accepted_steps"]), int(ds.attrs["control_rejected_steps"])


def main_(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scene", choices=["two", "om"], default="two")
    p.add_argument("--k", default="0,1,2")
    p.add_argument("--tolerances", default="1e-3,1e-4,1e-5,1e-6")
    p.add_argument("--fixed", default="", help="fixed macro-step sizes to try (om)")
    a = p.parse_args(argv)
    tols = [float(t) for t in a.tolerances.split(",")]
    print("| k | tolerance | error at t_end | accepted steps | rejected |\n|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for k in (int(s) for s in a.k.split(",")):
            path = scene(a.scene, tmp, k)
            for n, tol in enumerate(tols):
                got = controlled(a.scene, path, tol, tmp / f"run{k}_{n}.nc")
                text = "failed" if got is None else f"{got[0]:.3g} | {got[1]} | {got[2]}"
                print(f"| {k} | {tol:g} | {text} |", flush=True)
            for H in (float(h) for h in a.fixed.split(",") if h):
                with contextlib.redirect_stdout(io.StringIO()):
                    run = run_scene(om_scene(tmp, "baumgarte", k, H, 1000 * H, BAUMGARTE))
                print(f"fixed k = {k}, H = {H:g} s, 1000 steps: {run.status}", flush=True)


if __name__ == "__main__":
    main_()
