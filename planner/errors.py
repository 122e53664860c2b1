"""Exception types of the package: every bad input raises one of these."""


class PlannerError(ValueError):
    """Base class of every error the package raises on bad input."""


class LatticeError(PlannerError):
    """Bad lattice definition or bad points given to a lattice."""


class MapError(PlannerError):
    """Unreadable, corrupt or inconsistent map or point-cloud input."""


class PlanError(PlannerError):
    """Bad planning request (start/goal outside the map or inside an obstacle, ...)."""
