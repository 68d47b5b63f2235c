"""The force-driven test unit (fmus/msd) written in Python and exported with pythonfmu (fmus/README.md).

m x'' = -c x - c3 x^3 - d x' + lambda (``c3 = 0`` by default: the linear unit; a cubic spring makes it a
nonlinear one) with lambda held constant over each doStep (the unit cannot interpolate inputs:
icosim hands it the coupling polynomial as sub-steps); the step is integrated by classical Runge-Kutta with
``internal_steps`` steps.  Its state is its registered variables, which pythonfmu saves and restores
(``--handle-state``).
"""

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real


class msd_python(Fmi2Slave):  # noqa: N801 - pythonfmu names the model after the class
    author = "icosim"
    description = "Mass-spring-damper to ground driven by a force (Python, pythonfmu)"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.m, self.c, self.d, self.c3 = 1.0, 1000.0, 2.0, 0.0
        self.x0 = self.v0 = 0.0
        self.internal_steps = 20.0
        self.lam = 0.0
        self.x = self.v = 0.0
        fixed = dict(causality=Fmi2Causality.parameter, variability=Fmi2Variability.fixed)
        for name in ("m", "c", "d", "c3", "x0", "v0", "internal_steps"):
            self.register_variable(Real(name, **fixed))
        self.register_variable(Real("lam", causality=Fmi2Causality.input, variability=Fmi2Variability.continuous))
        continuous = dict(causality=Fmi2Causality.output, variability=Fmi2Variability.continuous)
        for name in ("x", "v"):
            self.register_variable(Real(name, **continuous))
        # the acceleration follows the input directly (what icosim re-evaluates at a fixed end state)
        self.register_variable(Real("a", getter=lambda: self._acc(self.x, self.v), **continuous))

    def exit_initialization_mode(self):
        self.x, self.v = self.x0, self.v0

    def _acc(self, x, v):
        return (-self.c * x - self.c3 * x**3 - self.d * v + self.lam) / self.m

    def do_step(self, current_time, step_size):
        n = max(1, int(self.internal_steps))
        h = step_size / n
        x, v = self.x, self.v
        for _ in range(n):
            k1x, k1v = v, self._acc(x, v)
            k2x, k2v = v + h / 2 * k1v, self._acc(x + h / 2 * k1x, v + h / 2 * k1v)
            k3x, k3v = v + h / 2 * k2v, self._acc(x + h / 2 * k2x, v + h / 2 * k2v)
            k4x, k4v = v + h * k3v, self._acc(x + h * k3x, v + h * k3v)
            x += h / 6 * (k1x + 2 * k2x + 2 * k3x + k4x)
            v += h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
        self.x, self.v = x, v
        return True
