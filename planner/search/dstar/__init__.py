"""D* Lite: the planner (:mod:`~.lite`, :class:`DStarLite`), its repair kernels (:mod:`~.kernel`)
and the one-call replan (:mod:`~.replan`)."""
