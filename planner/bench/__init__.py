"""The benchmark suite: which lattice should my map and my planner use?

Modules: ``suite`` (TOML definitions -> runs), ``queries`` (start/goal pairs valid for
every lattice), ``metrics`` (clearance against the raw obstacles), ``runner`` (local
processes or Dask, append-only results, resume), ``summary`` (tables, figures, report).
"""
