"""The benchmark suite: which lattice should my map and my planner use?

Modules: ``suite`` (TOML definitions -> runs), ``rotations`` (the random rotations of the
paper's fairness rule), ``worlds`` (the World of a rotated map, cached for the workers),
``queries`` (start/goal pairs valid for every lattice, in observed free space), ``metrics``
(clearance against the raw obstacles), ``runner`` (local processes or Dask, append-only
results, resume), ``paired`` (lattice vs cubic per query: intervals, tests, generated
sentences), ``summary`` (tables, box plots, report), ``figures`` (trade-off curves),
``session`` (one ``planner bench`` run).
"""
