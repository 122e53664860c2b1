"""A*, Dijkstra, Theta* and Lazy Theta*: the resumable kernel with its any-angle rules
(:mod:`~.kernel`) and the Python driver that sizes its arrays (:mod:`~.driver`)."""
