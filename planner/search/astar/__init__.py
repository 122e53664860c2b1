"""A*, Dijkstra, Theta* and Lazy Theta*: the resumable kernel with its any-angle rules
(:mod:`~.kernel`), its loop for lattice methods on dense grids (:mod:`~.dense`) and the
Python driver that keeps and sizes its arrays (:mod:`~.driver`)."""
