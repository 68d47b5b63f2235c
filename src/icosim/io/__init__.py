"""How results become files: self-describing NetCDF with provenance, checksums, strict JSON.

==========================  ===================================================
module                      holds
==========================  ===================================================
:mod:`.netcdf`              provenance attributes, atomic NetCDF writing and
                            checked reading (every part's datasets)
:mod:`.integrity`           a SHA-256 beside each dataset, corrupt files set
                            aside, stale temporaries removed
:mod:`.jsonio`              strict JSON (no NaN or Infinity) for every file and
                            answer icosim writes
:mod:`.yamlio`              safe YAML through libyaml where PyYAML has it (the
                            configuration, claims and scene files)
==========================  ===================================================

The package imports none of its modules.  (``icosim.sources``, the modules a job's script
rests on, reads the package's source rather than writing results: it stays at the top level.)
"""
