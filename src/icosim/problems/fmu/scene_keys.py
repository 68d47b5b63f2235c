"""The keys of a scene of joints and what they hold (:mod:`icosim.problems.fmu.scene` checks a scene against them;
a scene of joints beside connections, :mod:`icosim.problems.fmu.joint_signal_scene`, reads them too)."""

__all__ = ["SUBSYSTEM_KEYS", "JOINT_KEYS", "SCENE_KEYS", "COUPLING_KEYS"]

#: Keys of one subsystem and what they hold.
SUBSYSTEM_KEYS = {
    "fmu": "the unit: an .fmu file or a source directory, relative to the scene file",
    "start": "start values of the unit's parameters and inputs",
    "position": "name of the position output (a drive without it: its point's position is the prescribed one)",
    "velocity": "name of the velocity output (a drive without it: its point's velocity is the prescribed one)",
    "acceleration": "name of the acceleration output (a drive without it: the prescribed acceleration)",
    "force": "name of the coupling-force input (a force-driven subsystem)",
    "acceleration_input": "name of the prescribed-acceleration input (a kinematically driven subsystem)",
    "reaction_force": "name of the output of the force the drive exerts (a kinematically driven subsystem)",
    "position_input": "name of the prescribed-position input (a kinematically driven subsystem: a drive)",
    "velocity_input": "name of the prescribed-velocity input (a kinematically driven subsystem: a drive)",
    "force_sign": "+1 or -1: with joints, the unit's input is force_sign times the sum of its joints' multipliers "
    "(+lambda_j on a joint's first subsystem, -lambda_j on its second); without joints, the coupling force on "
    "this subsystem is force_sign * lambda",
    "mass": "the mass (a number, or the name of a unit variable holding it): the projection's weight",
    "set_position": "name of a tunable parameter or input that sets the position (projection)",
    "set_velocity": "name of a tunable parameter or input that sets the velocity (projection)",
    "rollback_tolerance": "relative difference accepted when a restored step is repeated (default 1e-12; 0: bit for bit)",
    "interface": "auto (default: co-simulation where the unit can roll back, else model exchange), co-simulation "
    "or model-exchange",
    "tolerance": "the integrator's relative tolerance of a model exchange unit (default 1e-10)",
    "record": "names of unit variables (outputs, locals, parameters, inputs) written to the dataset as "
    "<subsystem>.<variable>(time), read at t_start and after each accepted macro step",
}

#: Keys of one joint and what they hold.
JOINT_KEYS = {
    "between": "the two subsystems the joint holds together, its first and its second side: the joint's "
    "multiplier acts with +lambda_j on the first and -lambda_j on the second",
    "decomposition": "which side is force driven and which kinematically driven (first side, second side)",
}

#: Top-level keys of a scene and what they hold.
SCENE_KEYS = {
    "subsystems": "the units by name (two without joints, the first the paper's subsystem 1; any number >= 2 "
    "with joints)",
    "system": "an SSP or OSP system file (or its folder), relative to the scene: its components are the subsystems",
    "joints": "the joints between the subsystems, each {between: [first, second], decomposition} (without it: "
    "the two subsystems joined by coupling.decomposition)",
    "coupling": "the method, decomposition (without joints), k, scheme (and order), H and their options",
    "t_start": "the start time (s; default 0)",
    "t_end": "the end time (s)",
    "initial_coupling": "the coupling variables at t_start, every component (default: computed from the units)",
    "initial": "check (default: refuse a joint whose positions or velocities differ at t_start), project (move "
    "the units onto the joints) or as-is (run, and report the gap)",
    "initial_tolerance": "the gap accepted at t_start, relative to max(1, the largest position or velocity)",
    "divergence_bound": "a state (SI) beyond this ends the run as diverged (default 1e10 (1 + |state at t_start|))",
    "limits": "call_seconds: the longest an FMI call of a unit may take; identify_seconds: the longest the "
    "identification of one unit may take (--predict)",
}

#: Coupling keys besides the method's parameters, and their defaults.
COUPLING_KEYS = {
    "method": None,
    "decomposition": None,
    "k": None,
    "scheme": "jacobi",
    "order": None,
    "H": None,
    "iterations": 1,
    "inputs": "auto",
    "substeps": 16,
    "perturbation": 1.0e-3,
    "sensitivities": "each-step",
    "control": None,  # controlled macro steps (icosim.problems.fmu.controlled); None: H fixed
}
