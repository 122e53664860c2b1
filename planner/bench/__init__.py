"""The benchmark suite: which lattice should my map and my planner use?

Modules: ``suite`` (TOML definitions -> runs), ``rotations`` (the random rotations of the
paper's fairness rule), ``worlds`` (the World of a rotated map, cached for the workers),
``queries`` (start/goal pairs valid for every lattice, in observed free space), ``metrics``
(clearance against the raw obstacles), ``tasks`` (a suite expanded into batches of
queries), ``task`` (one batch run in a worker), ``rows`` (the append-only results file),
``runner`` (local processes or Dask, resume), ``stopping`` (SIGINT / SIGTERM), ``host``
(the machine a row ran on), ``paired`` (lattice vs cubic per query: intervals, tests, generated
sentences), ``orientation`` (the permutation test of rotation labels), ``answer`` (the time
to the delivered path, the queries each lattice cannot run, the decision table),
``summary`` (tables, box plots, report), ``figures`` (trade-off curves),
``session`` (one ``planner bench`` run).
"""
