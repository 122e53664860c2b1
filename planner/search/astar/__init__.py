"""A*, Dijkstra, Theta* and Lazy Theta*: the resumable kernel (:mod:`~.kernel`), its any-angle
rules (:mod:`~.theta`) and the Python driver that sizes its arrays (:mod:`~.driver`)."""
