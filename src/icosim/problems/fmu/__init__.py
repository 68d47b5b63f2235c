"""FMU scenes: the implicit coupling methods on people's own co-simulation units (FMI 2.0 and 3.0 co-simulation; docs/fmi.md).

==================  ===========================================================================
module              holds
==================  ===========================================================================
:mod:`.scene`       scene files (YAML) checked against a JSON schema before anything is loaded
:mod:`.units`       one FMU instance: loaded, checked, stepped with a polynomial input, saved, restored
:mod:`.problem`     two units as a :class:`~icosim.engine.problem.CosimulationProblem`
:mod:`.run`         a scene run through :func:`icosim.engine.macrostep.macro_step`, as a dataset
:mod:`.predict`     linear units identified from probing steps, the spectral radius of every scheme
:mod:`.build`       units built from source (``fmus/``) with fmpy's CMake project, cached
:mod:`.errors`      what a scene, a unit or a step can fail with
==================  ===========================================================================

fmpy is imported only when a unit is opened or built (the ``fmi`` extra installs it).
"""
