"""The paper's measurements and the cross-lattice comparison.

Modules: ``measure`` (quantization quality, neighbour distances, Table I), ``paper``
(reproduces the paper's figures: ``planner stats``), ``compare`` (the same queries on every
lattice: ``planner compare``; path files and figures), ``tables`` (the one table formatter),
``metadata`` (what every report records about its run).
"""
