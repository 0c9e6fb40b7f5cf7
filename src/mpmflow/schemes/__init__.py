"""Time-integration schemes, registered by the name used in ``solver.scheme``."""

SCHEMES = {}


def register(name):
    def deco(cls):
        SCHEMES[name] = cls
        return cls
    return deco


def make_scheme(case, grid, particles):
    from . import explicit, projection  # noqa: F401  (they register themselves)

    return SCHEMES[case.solver.scheme](case, grid, particles)
