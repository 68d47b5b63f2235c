"""FMU scenes: the implicit coupling methods on people's own co-simulation units (FMI 2.0 and 3.0, co-simulation and model exchange; docs/fmi.md).

====================  ===========================================================================
module                holds
====================  ===========================================================================
:mod:`.scene`         scene files (YAML) checked against a JSON schema before anything is loaded
:mod:`.description`   a unit's model description and the kind of unit a scene can couple
:mod:`.variables`     typed variables, array elements, start values by the standard's rules
:mod:`.measures`      units of measure of the coupling variables, converted to SI
:mod:`.units`         one FMU instance: opened, stepped with a polynomial input, saved, restored
:mod:`.fmi`           a unit's FMI calls: one adapter per version (2.0, 3.0) over fmpy's documented API
:mod:`.exchange`      a model exchange unit integrated by icosim, its states kept by icosim
:mod:`.drives`        a kinematic drive's position, velocity and acceleration inputs over a macro step
:mod:`.findings`      a check's finding
:mod:`.inspection`    a unit checked before it is trusted: rollback, feedthrough, direction, role
:mod:`.motion`        a unit must move as it says: the doStep flag, the trapezoid and sub-step checks
:mod:`.roles`         roles that fit the unit: force driven, kinematically driven, compliant
:mod:`.check`         ``icosim cosim --check``: every check as a table
:mod:`.guard`         the supervised run: a unit that hangs or crashes named
:mod:`.pythonfmu`     pythonfmu's interpreter state released before the process exits
:mod:`.problem`       units and joints as a :class:`~icosim.engine.problem.CosimulationProblem`
:mod:`.consistent`    the consistent initial coupling at ``t_start``
:mod:`.checkpoint`    the FMU problem's checkpoint and its macro step of varying size
:mod:`.controlled`    ``coupling.control``: a scene's controlled macro steps
:mod:`.run`           a scene run through the engine's run loop, its start, its dataset
:mod:`.initial`       a scene's ``initial_coupling`` against the units' own
:mod:`.record`        the variables a scene asks to record
:mod:`.predict`       linear units identified from probing steps, the spectral radius of every scheme
:mod:`.dual_mass`     OMSimulator's DualMassOscillator: the exact solution of its units' equations
:mod:`.build`         units built from source (``fmus/``) with fmpy's CMake project, cached
:mod:`.errors`        what a scene, a unit or a step can fail with
====================  ===========================================================================

fmpy is imported only when a unit is opened or built (the ``fmi`` extra installs it).
"""
