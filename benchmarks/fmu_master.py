"""The co-simulation master's wall time per macro step against the floor of its own FMI calls, side by side.

For one configuration (units, coupling graph, method, ``k``, scheme, sensitivities) the master -- the engine's
:func:`icosim.engine.run.simulate` on an :class:`~icosim.problems.fmu.problem.FmuCosimulation` of a scene's units
or of test units ``fmus/msd`` (force driven, different masses) -- runs ``--steps`` macro steps.  Once, untimed,
every FMI call it makes is recorded at the fmpy level: each ``fmi2*`` method of every unit's ``FMU2Slave`` (the
functions fmpy's own ``setReal``, ``doStep``, ... go through) is wrapped on the instance, and so is each function
of its loaded library (``fmu.dll``, which the master calls itself), so nothing the units are asked escapes the
count.  From that record a **bare fmpy loop** is built that makes exactly the same calls on fresh instances of
the same units, in the same order, with the same value references and values: the floor.  A second, untimed
pass of the bare loop under the same wrappers checks that it makes the same calls per kind with the same value
sizes.  Three floors are timed:

* ``api``: fmpy's documented methods (``setReal(vrs, values)``, ``getReal``, ``setRealInputDerivatives``,
  ``doStep``, ``getFMUstate``, ``setFMUstate``, ``freeFMUstate``), the loop a user would write -- the floor the
  target (master <= 2 x floor) is stated against;
* ``raw``: the same calls to the functions of the units' libraries as fmpy loaded them (``fmu.dll.fmi2*``,
  which the master calls too) with every ctypes argument built before the clock starts and no status looked
  at (reported for honesty: it is what is left when Python builds and checks nothing).

* ``strict``: counted from what the run reports rather than recorded: per
  unit, as many integrations as its ``doStep`` calls in the run, each through fmpy's own ``FMU2Slave`` methods
  in a bare loop on the same unit -- restore (as many as the run restored), set the input and its derivatives,
  ``doStep``, read the outputs -- and as many saves (save and free) as the run saved; the smallest of a timing
  before the runs (fresh units) and one after each run (on the run's units).  It leaves out the calls the
  master makes beyond an integration (the input set to ``u(1)`` after each step so the outputs read are those at
  ``T_N+1``; a finished unit's outputs re-evaluated at its end state, a set and a read without a step), and it
  makes no per-call Python work of a recorded replay (no list of operations in memory).  The lowest floor.

The master is timed twice: in the process itself (``engine``: the bare engine loop, no records) and as users run
it (``cosim``): inside :func:`icosim.problems.fmu.guard.supervised`, the forked child of ``icosim cosim`` whose
every FMI call writes the shared call record, with the run loop's divergence bound and per-step observer as
:func:`icosim.problems.fmu.run.run_scene` calls it.  Units are opened fresh for every timed run (not timed); each
number is the best of ``--repeat`` runs, the four kinds interleaved.

Configurations: the scenes ``config/scenes/{two_mass_{ff,fd,dd,mm},chain3,chain10}.yaml`` as they are (units opened
and checked, coupling and start as ``icosim cosim`` makes them); the pair of ``fmus/msd`` units (ff, k = 1;
projection under Jacobi and gauss-seidel-12, Baumgarte index 1 under Jacobi; sensitivities first-step and
each-step); the 10-unit chain (``CouplingGraph.chain(["ff"] * 9, ports="one")``, the same methods and schemes,
Gauss-Seidel 1..10); chains of N = 2 ... 64 units (each-step; Baumgarte index 1 under Jacobi, projection under
Gauss-Seidel 1..N) for the exponent of time over N (a least-squares fit of log time against log N). Baumgarte index
1 (mu = H) under Gauss-Seidel diverges on these force-driven units within 200 steps, so it is not timed there.

With ``--old COMMIT`` the same measurement runs for that commit too (a ``git worktree``, its ``src`` first on
``PYTHONPATH``), in a fresh process per tree, old - this tree - old; the JSON has both.  Never a timed assertion:
a measurement to quote (docs/benchmarks.md).

    python benchmarks/fmu_master.py [--steps 200 | --simulated 30] [--repeat 5] [--only scenes,pair,chain10,scaling]
                                    [--floors api,raw,strict] [--old COMMIT] [--sizes 2,4,8,16,32,64] [--json FILE]

``--simulated SECONDS`` runs each configuration over that much simulated time (30 s: 30000 macro steps of the
pair), so that one-off work does not count; a recorded floor of so many calls needs much memory, so such a run
is best made with ``--floors strict``.
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
H = 1e-3
SCENES = ("two_mass_ff", "two_mass_fd", "two_mass_dd", "two_mass_mm", "chain3", "chain10")  # config/scenes, as they are
NAMES = dict(position="x", velocity="v", acceleration="a", force="lambda", set_position="x_set", set_velocity="v_set")

# -- configurations ----------------------------------------------------------------------------------------------


def gauss_seidel(n: int) -> str:
    return "gauss-seidel-" + ("" if n < 10 else ".").join(str(i + 1) for i in range(n))


def configurations(only, sizes):
    out = []
    if "scenes" in only:
        for name in SCENES:
            out.append(dict(group="scenes", scene=name))
    # Baumgarte (index 1, mu = H) under Gauss-Seidel diverges on these chains of force-driven units within
    # 200 steps; a diverging run times overflowing numbers, so Gauss-Seidel is measured with projection.
    pairs = [(m, s) for m in ("projection", "baumgarte") for s in ("jacobi", "gs") if (m, s) != ("baumgarte", "gs")]
    if "pair" in only:
        for method, scheme in pairs:
            for sens in ("first-step", "each-step"):
                s = "jacobi" if scheme == "jacobi" else gauss_seidel(2)
                out.append(dict(group="pair", n=2, method=method, scheme=s, sensitivities=sens))
    if "chain10" in only:
        for method, scheme in pairs:
            for sens in ("first-step", "each-step"):
                s = "jacobi" if scheme == "jacobi" else gauss_seidel(10)
                out.append(dict(group="chain10", n=10, method=method, scheme=s, sensitivities=sens))
    if "scaling" in only:
        for scheme, method in (("jacobi", "baumgarte"), ("gauss-seidel", "projection")):
            for n in sizes:
                s = "jacobi" if scheme == "jacobi" else gauss_seidel(n)
                out.append(dict(group=f"scaling-{scheme}", n=n, method=method, scheme=s, sensitivities="each-step"))
    return out


def label(cfg) -> str:
    if "scene" in cfg:
        return f"scene {cfg['scene']}"
    scheme = cfg["scheme"] if len(cfg["scheme"]) < 20 else "gauss-seidel-1..N"
    method = "baumgarte index 1" if cfg["method"] == "baumgarte" else cfg["method"]
    return f"N={cfg['n']} {method} {scheme} {cfg['sensitivities']}"


# -- the master ----------------------------------------------------------------------------------------------------


class Setup:
    """Units opened, the problem, its consistent start, the method: everything before the first macro step."""

    def __init__(self, fmu, cfg):
        from icosim.engine.graph import CouplingGraph
        from icosim.engine.methods import engine_method, make_method
        from icosim.problems.fmu.problem import Coupling, FmuCosimulation
        from icosim.problems.fmu.units import Unit

        self.cfg = cfg
        if "scene" in cfg:
            return self._scene(cfg["scene"])
        n = cfg["n"]
        self.units = []
        for i in range(n):
            start = {"m": 1.0 + 0.5 * i, "c": 1000.0, "d": 2.0, "x0": 0.1}
            self.units.append(Unit(f"body{i + 1}", fmu, NAMES, start, inputs="derivatives", t0=0.0))
        couplings = [Coupling("force", 1, 1.0 + 0.5 * i) for i in range(n)]
        graph = CouplingGraph.pair("ff") if n == 2 else CouplingGraph.chain(["ff"] * (n - 1), ports="one")
        self.problem = FmuCosimulation(self.units, couplings, graph, 1, H, sensitivities=cfg["sensitivities"])
        method = make_method("baumgarte", index=1, mu=H) if cfg["method"] == "baumgarte" else make_method("projection")
        self.method = engine_method(method, H)
        self.state = self.problem.initial_state()
        self.history = self.problem.initial_history(self.problem.consistent_coupling())
        self.scheme, self.iterations, self.bound = cfg["scheme"], 1, None

    def _scene(self, name):
        """The scene's units opened and checked, its problem and consistent start, as ``run_scene`` makes them."""
        from icosim.problems.fmu.problem import FmuCosimulation
        from icosim.problems.fmu.run import consistent_start, divergence_bound, open_units
        from icosim.problems.fmu.scene import load_scene

        scene = load_scene(ROOT / "config" / "scenes" / f"{name}.yaml")
        c = scene.coupling
        self.units, couplings = open_units(scene, cache=ROOT / "build" / "fmus")
        self.problem = FmuCosimulation(
            self.units, couplings, scene.graph(len(self.units[0].elements["position"])), c["k"], c["H"],
            t0=float(scene.data.get("t_start", 0.0)), perturbation=c["perturbation"], sensitivities=c["sensitivities"],
        )  # fmt: skip
        start = consistent_start(scene, self.problem)
        self.method, self.state, self.history = scene.method, start.state, start.history
        self.scheme, self.iterations, self.bound = c["scheme"], c["iterations"], divergence_bound(scene, start.state)

    def run(self, steps, *, as_users=False):
        """``steps`` macro steps; ``as_users``: the run loop's arguments as ``run_scene`` gives them."""
        import numpy as np

        from icosim.engine.run import simulate

        kw = dict(scheme=self.scheme, iterations=self.iterations)
        if as_users:
            bound = self.bound if self.bound is not None else 1e10 * (1.0 + float(np.max(np.abs(self.state))))
            kw.update(bound=bound, observe=lambda n, state, history, y: None)
        before = counters(self.units)
        t = time.perf_counter()
        with np.errstate(over="ignore", invalid="ignore"):
            traj = simulate(self.problem, self.method, self.state, self.history, steps, **kw)
        wall = time.perf_counter() - t
        if traj.steps != steps:
            raise SystemExit(f"{label(self.cfg)}: the run stopped at step {traj.steps}: {traj.reason}")
        self.last = traj.states[-1]
        #: per unit, the run's doStep calls, saved and restored states, as the unit reports them
        self.counts = [tuple(b - a for a, b in zip(x, y)) for x, y in zip(before, counters(self.units))]
        return wall

    def close(self):
        self.problem.close()
        for u in self.units:
            u.close()


def counters(units):
    """Per unit: doStep calls, states saved, states restored, as the unit counts them."""
    return [(u.do_steps, u.saved, u.restored) for u in units]


# -- the strict floor: the run's integrations as a bare fmpy loop on the same units ------------------------------


def strict_jobs(s, counts):
    """Per unit of the setup ``s`` (opened, at any point of a run) the bare loop's work for the run's ``counts``
    (:attr:`Setup.counts`): its input and output value references, input derivatives of the run's order, and a
    saved state to restore (saved before the clock starts)."""
    jobs = []
    for i, (u, (steps, saved, restored)) in enumerate(zip(s.units, counts)):
        key = s.problem.couplings[i].input_key
        key = key if key in u.elements else "drive"
        ins = [el.value_reference for el in u.elements[key]]
        outs = [el.value_reference for k in ("position", "velocity", "acceleration", "reaction_force")
                if k in u.elements for el in u.elements[k]]  # fmt: skip
        k = s.problem.k
        orders = [m for m in range(1, k + 1) for _ in ins] if u.exact_inputs else []
        jobs.append((u.fmu, ins, [0.0] * len(ins), (ins * k, orders), [0.0] * len(orders), outs, steps, saved, restored,
                     u.t, s.problem.H / (1 if u.exact_inputs else u.substeps)))  # fmt: skip
    return [(job, job[0].getFMUstate()) for job in jobs]


def run_strict(jobs):
    """The strict floor, timed: per unit, as many integrations as the run made (restore where the run restored,
    set the input and its derivatives, doStep, read the outputs), then its saves (save and free), through fmpy's
    own ``FMU2Slave`` methods; every unit's saved state freed after the clock stops."""
    t = time.perf_counter()
    for (fmu, ins, values, which, derivatives, outs, steps, saved, restored, t0, h), state in jobs:
        for j in range(steps):
            if j < restored:
                fmu.setFMUstate(state)
            fmu.setReal(ins, values)
            if which[1]:  # (value references, orders) of the derivatives
                fmu.setRealInputDerivatives(*which, derivatives)
            fmu.doStep(t0 if j < restored else t0 + (j - restored + 1) * h, h, False)
            fmu.getReal(outs)
        for _ in range(restored - steps):
            fmu.setFMUstate(state)
        for _ in range(saved):
            fmu.freeFMUstate(fmu.getFMUstate())
    wall = time.perf_counter() - t
    for job, state in jobs:
        job[0].freeFMUstate(state)
    return wall


# -- recording FMI calls at the fmpy level -------------------------------------------------------------------------


class Recorder:
    """Wraps every ``fmi2*`` function of the units' fmpy instances; records ``(unit, function, payload)``."""

    def __init__(self, fmus):
        self.calls = []
        self.handles = {}  # address of a live FMU state -> slot
        self.slots = 0
        self.pre = []  # (unit, slot) of states saved before the record began
        self.fmus = fmus
        for u, fmu in enumerate(fmus):
            for name in dir(type(fmu)):
                if name.startswith("fmi2") and callable(getattr(fmu, name)):
                    setattr(fmu, name, self._wrap(u, name, getattr(fmu, name)))
                    # the library's function too, which the units call themselves (fmpy's methods call the
                    # function they loaded, not this attribute: a call is recorded once either way)
                    setattr(fmu.dll, name, self._wrap(u, name, getattr(fmu.dll, name)))

    def _slot(self, u, address, new=False):
        if new or address not in self.handles:
            self.handles[address] = self.slots
            if not new:
                self.pre.append((u, self.slots))
            self.slots += 1
        return self.handles[address]

    def _wrap(self, u, name, f):
        def wrapped(*args):
            res = f(*args)
            self.calls.append((u, name, self._payload(u, name, args)))
            return res

        wrapped.__wrapped__ = f
        return wrapped

    def _payload(self, u, name, args):
        if name in ("fmi2SetReal", "fmi2GetReal"):
            _, vr, n, value = args
            return (tuple(vr[:n]), tuple(value[:n]) if name == "fmi2SetReal" else None)
        if name == "fmi2SetRealInputDerivatives":
            _, vr, n, order, value = args
            return (tuple(vr[:n]), tuple(order[:n]), tuple(value[:n]))
        if name == "fmi2DoStep":
            return tuple(args[1:])
        if name == "fmi2GetFMUstate":
            return self._slot(u, args[1]._obj.value, new=True)
        if name == "fmi2SetFMUstate":
            return self._slot(u, args[1].value)
        if name == "fmi2FreeFMUstate":
            address = args[1]._obj.value
            slot = self._slot(u, address)
            del self.handles[address]
            return slot
        return None

    def unwrap(self):
        for fmu in self.fmus:
            for name in [n for n in vars(fmu) if n.startswith("fmi2")]:
                delattr(fmu, name)
                setattr(fmu.dll, name, getattr(fmu.dll, name).__wrapped__)

    def counts(self, steps):
        """Per kind: calls per macro step, and the value sizes seen (``nvr``)."""
        out = collections.Counter(name for _, name, _ in self.calls)
        sizes = collections.defaultdict(collections.Counter)
        for _, name, payload in self.calls:
            if name in ("fmi2SetReal", "fmi2GetReal", "fmi2SetRealInputDerivatives"):
                sizes[name][len(payload[0])] += 1
        return (
            {k.removeprefix("fmi2"): v / steps for k, v in sorted(out.items())},
            {k.removeprefix("fmi2"): dict(v) for k, v in sorted(sizes.items())},
        )


def fmus_of(units):
    return [u.fmu for u in units]


# -- the bare fmpy loop ---------------------------------------------------------------------------------------------


def _get_state(fmu, slots, k):
    slots[k] = fmu.getFMUstate()


def _set_state(fmu, slots, k):
    fmu.setFMUstate(slots[k])


def _free_state(fmu, slots, k):
    fmu.freeFMUstate(slots.pop(k))


def bare_api(fmus, calls, slots):
    """The recorded calls as fmpy's documented methods, ``(function, arguments)`` each."""
    ops = []
    for u, name, p in calls:
        fmu = fmus[u]
        if name == "fmi2SetReal":
            ops.append((fmu.setReal, (list(p[0]), list(p[1]))))
        elif name == "fmi2GetReal":
            ops.append((fmu.getReal, (list(p[0]),)))
        elif name == "fmi2SetRealInputDerivatives":
            ops.append((fmu.setRealInputDerivatives, (list(p[0]), list(p[1]), list(p[2]))))
        elif name == "fmi2DoStep":
            ops.append((fmu.doStep, p))
        elif name == "fmi2GetFMUstate":
            ops.append((_get_state, (fmu, slots, p)))
        elif name == "fmi2SetFMUstate":
            ops.append((_set_state, (fmu, slots, p)))
        elif name == "fmi2FreeFMUstate":
            ops.append((_free_state, (fmu, slots, p)))
        else:
            raise SystemExit(f"the master called {name}: the bare loop does not know it")
    return ops


def bare_raw(fmus, calls, slots):
    """The recorded calls through the functions of the units' libraries as fmpy loaded them (``fmu.dll``), every
    ctypes argument built beforehand, no status looked at."""
    from ctypes import byref, c_double, c_int, c_uint

    from fmpy.fmi2 import fmi2FMUstate

    states = collections.defaultdict(fmi2FMUstate)
    ops = []
    for u, name, p in calls:
        fmu = fmus[u]
        comp, lib = fmu.component, fmu.dll
        if name == "fmi2SetReal":
            n = len(p[0])
            ops.append((lib.fmi2SetReal, (comp, (c_uint * n)(*p[0]), n, (c_double * n)(*p[1]))))
        elif name == "fmi2GetReal":
            n = len(p[0])
            ops.append((lib.fmi2GetReal, (comp, (c_uint * n)(*p[0]), n, (c_double * n)())))
        elif name == "fmi2SetRealInputDerivatives":
            n = len(p[0])
            args = (comp, (c_uint * n)(*p[0]), n, (c_int * n)(*p[1]), (c_double * n)(*p[2]))
            ops.append((lib.fmi2SetRealInputDerivatives, args))
        elif name == "fmi2DoStep":
            ops.append((lib.fmi2DoStep, (comp, *p)))
        elif name == "fmi2GetFMUstate":
            ops.append((lib.fmi2GetFMUstate, (comp, byref(states[p]))))
        elif name == "fmi2SetFMUstate":
            ops.append((lib.fmi2SetFMUstate, (comp, slots[p] if p in slots else states[p])))
        elif name == "fmi2FreeFMUstate":
            ops.append((lib.fmi2FreeFMUstate, (comp, byref(slots[p] if p in slots else states[p]))))
    return ops


def run_ops(ops):
    t = time.perf_counter()
    for f, args in ops:
        f(*args)
    return time.perf_counter() - t


# -- one configuration --------------------------------------------------------------------------------------------


def record(fmu, cfg, steps, recorded=True):
    """The master's FMI calls over ``steps`` macro steps (untimed; ``recorded`` False: not recorded), its end state
    and its units' counts (:attr:`Setup.counts`)."""
    s = Setup(fmu, cfg)
    rec = Recorder(fmus_of(s.units)) if recorded else None
    s.run(steps)
    if rec is not None:
        rec.unwrap()
    end, counts = s.last, s.counts
    s.close()
    return rec, end, counts


def bare_setup(fmu, cfg, rec, kind, *, recorded=False):
    """Fresh units at the master's start (opened and started the same way), and the bare loop's operations
    (``recorded``: its calls recorded too, :attr:`Setup.recorder`)."""
    s = Setup(fmu, cfg)
    fmus = fmus_of(s.units)
    s.recorder = Recorder(fmus) if recorded else None
    slots = {}
    for u, slot in rec.pre:  # states saved before the record began: saved now, as the master had them
        slots[slot] = fmus[u].getFMUstate()
    ops = (bare_api if kind == "api" else bare_raw)(fmus, rec.calls, slots)
    return s, ops, slots


def verify(fmu, cfg, rec, steps):
    """The bare loop (both kinds) makes the master's calls: same kinds, counts and value sizes."""
    for kind in ("api", "raw"):
        s, ops, _ = bare_setup(fmu, cfg, rec, kind, recorded=True)
        check = s.recorder
        check.calls.clear()  # the states saved before the loop
        run_ops(ops)
        check.unwrap()
        s.close()
        if check.counts(steps) != rec.counts(steps):
            raise SystemExit(
                f"{label(cfg)}: the bare loop ({kind}) made {check.counts(steps)}, the master {rec.counts(steps)}"
            )
        if [(u, n) for u, n, _ in check.calls] != [(u, n) for u, n, _ in rec.calls]:
            raise SystemExit(f"{label(cfg)}: the bare loop ({kind}) made the calls in another order")


def time_cosim(fmu, cfg, steps):
    """The master as ``icosim cosim`` runs it: in the supervised child, the guard's records on."""
    from icosim.problems.fmu.guard import supervised

    with tempfile.NamedTemporaryFile("r", suffix=".txt") as out:

        def target():
            s = Setup(fmu, cfg)
            wall = s.run(steps, as_users=True)
            s.close()
            Path(out.name).write_text(repr(wall))
            return 0

        outcome = supervised(target)
        if outcome.status != 0:
            raise SystemExit(f"{label(cfg)}: the supervised run failed: {outcome.message}")
        return float(Path(out.name).read_text())


def measure(fmu, cfg, steps, repeat, floors):
    import numpy as np

    recorded = "api" in floors or "raw" in floors
    rec, end, counts = record(fmu, cfg, steps, recorded)
    if recorded:
        verify(fmu, cfg, rec, steps)
    best = dict(engine=float("inf"), cosim=float("inf"), **{kind: float("inf") for kind in floors})
    if "strict" in floors:  # before the runs: fresh units at the master's start
        s = Setup(fmu, cfg)
        best["strict"] = run_strict(strict_jobs(s, counts))
        s.close()
    for _ in range(repeat):
        s = Setup(fmu, cfg)
        best["engine"] = min(best["engine"], s.run(steps))
        if not np.array_equal(s.last, end):
            raise SystemExit(f"{label(cfg)}: the master's end state changed between runs")
        if "strict" in floors:  # after a run: on the same units
            best["strict"] = min(best["strict"], run_strict(strict_jobs(s, counts)))
        s.close()
        for kind in ("api", "raw"):
            if kind in floors:
                s, ops, _ = bare_setup(fmu, cfg, rec, kind)
                best[kind] = min(best[kind], run_ops(ops))
                s.close()
        best["cosim"] = min(best["cosim"], time_cosim(fmu, cfg, steps))
    per_step = {k: 1e3 * v / steps for k, v in best.items()}  # ms per macro step
    out = dict(
        cfg,
        label=label(cfg),
        steps=steps,
        ms_per_step=per_step,
        unit_counts=counts,
        end_state=[[float(v) for v in row] for row in end],
    )
    for kind in floors:
        suffix = "" if kind == "api" else f"_{kind}"
        out[f"ratio_engine{suffix}"] = best["engine"] / best[kind]
        out[f"ratio_cosim{suffix}"] = best["cosim"] / best[kind]
    if recorded:
        out["calls_per_step"], out["value_sizes"] = rec.counts(steps)
        out["calls_match"] = True
    return out


def steps_of(cfg, steps, simulated):
    """Macro steps of a configuration: ``steps``, or as many as ``simulated`` seconds take at its step size."""
    if simulated is None:
        return steps
    h = H
    if "scene" in cfg:
        from icosim.problems.fmu.scene import load_scene

        h = load_scene(ROOT / "config" / "scenes" / f"{cfg['scene']}.yaml").coupling["H"]
    return int(round(simulated / h))


def exponents(results):
    import numpy as np

    out = {}
    for group in sorted({r["group"] for r in results if r["group"].startswith("scaling")}):
        rows = sorted((r for r in results if r["group"] == group), key=lambda r: r["n"])
        n = np.log([r["n"] for r in rows])
        out[group] = {
            key: float(np.polyfit(n, np.log([r["ms_per_step"][key] for r in rows]), 1)[0])
            for key in rows[0]["ms_per_step"]
        }
    return out


def child(args):
    import icosim

    src = str(Path(args.src).resolve())
    assert icosim.__file__.startswith(src), (icosim.__file__, src)
    from icosim.problems.fmu.build import build_unit

    fmu = build_unit(ROOT / "fmus" / "msd", ROOT / "build" / "fmus")
    sizes = [int(v) for v in args.sizes.split(",")]
    results = []
    floors = args.floors.split(",")
    for cfg in configurations(args.only.split(","), sizes):
        r = measure(fmu, cfg, steps_of(cfg, args.steps, args.simulated), args.repeat, floors)
        results.append(r)
        ms = r["ms_per_step"]
        print(f"{r['label']:<52} " + " ".join(f"{k} {v:7.4f}" for k, v in ms.items()) + " ms/step; "
              + " ".join(f"{k} {v:5.2f}" for k, v in r.items() if k.startswith("ratio_")),
              file=sys.stderr, flush=True)  # fmt: skip
    print(json.dumps(dict(results=results, exponents=exponents(results))))


# -- trees side by side ---------------------------------------------------------------------------------------------


def run_tree(src_root: Path, args, tag: str) -> dict:
    env = dict(os.environ, PYTHONPATH=str(src_root / "src"), OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    cmd = [
        sys.executable,
        __file__,
        "--child",
        "--src",
        str(src_root / "src"),
        "--steps",
        str(args.steps),
        "--repeat",
        str(args.repeat),
        "--only",
        args.only,
        "--sizes",
        args.sizes,
        "--floors",
        args.floors,
    ]
    if args.simulated is not None:
        cmd += ["--simulated", str(args.simulated)]  # fmt: skip
    print(f"== {tag} ({src_root})", file=sys.stderr, flush=True)
    proc = subprocess.run(cmd, env=env, stdout=subprocess.PIPE, text=True, check=True)
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=200, help="macro steps per timed run")
    ap.add_argument("--repeat", type=int, default=5, help="timed runs per kind (best taken)")
    ap.add_argument("--only", default="scenes,pair,chain10,scaling", help="groups: scenes, pair, chain10, scaling")
    ap.add_argument("--sizes", default="2,4,8,16,32,64", help="chain sizes of the scaling fit")
    ap.add_argument("--simulated", type=float, help="simulated seconds per timed run (instead of --steps)")
    ap.add_argument("--floors", default="api,raw,strict", help="floors timed: api, raw (recorded calls), strict")
    ap.add_argument("--old", help="another commit, measured before and after this tree")
    ap.add_argument("--json", help="write the numbers to this file")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--src", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        return child(args)
    out = {"steps": args.steps, "simulated": args.simulated, "repeat": args.repeat, "load": os.getloadavg()}
    if args.old:
        sys.path.insert(0, str(ROOT / "benchmarks"))
        from _workflow import tree

        with tree(args.old) as old:
            out["old_before"] = run_tree(old, args, f"{args.old} (before)")
            out["new"] = run_tree(ROOT, args, "this tree")
            out["old_after"] = run_tree(old, args, f"{args.old} (after)")
        out["old"] = args.old
    else:
        out["new"] = run_tree(ROOT, args, "this tree")
    summarise(out)
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=2))


def summarise(out):
    trees = [("new", "this tree")] + ([("old_before", f"{out['old']} before"), ("old_after", f"{out['old']} after")]
                                      if "old" in out else [])  # fmt: skip
    for key, name in trees:
        print(f"\n{name}:")
        for r in out[key]["results"]:
            ms = r["ms_per_step"]
            print(f"  {r['label']:<52} " + "  ".join(f"{k} {v:5.2f}" for k, v in r.items() if k.startswith("ratio_"))
                  + "  (ms/step: " + ", ".join(f"{k} {v:.4f}" for k, v in ms.items()) + ")")  # fmt: skip
        for group, fit in out[key]["exponents"].items():
            print(f"  exponent of time over N, {group}: " + ", ".join(f"{k} {v:.2f}" for k, v in fit.items()))
    if "old" in out:
        worst = max(
            _relative(a["end_state"], b["end_state"])
            for a, b in zip(out["new"]["results"], out["old_before"]["results"])
        )
        print(f"\nend states of this tree against {out['old']}: largest relative difference {worst:.3g}")


def _relative(a, b) -> float:
    import numpy as np

    a, b = np.asarray(a), np.asarray(b)
    scale = float(np.max(np.abs(b)))
    return float(np.max(np.abs(a - b))) / scale if scale else 0.0


if __name__ == "__main__":
    main()
