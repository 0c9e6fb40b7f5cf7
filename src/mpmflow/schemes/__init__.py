"""Time-integration schemes, registered by the name used in ``solver.scheme``, each
declaring what it supports (``SUPPORTS``): the case's rules ask here instead of naming
schemes."""

SCHEMES: dict[str, type] = {}

# The features a scheme may support, as the case's rules name them to the user.
FEATURES = {
    "obstacles": "fixed obstacles ([[obstacles]])",
    "materials": "materials other than inviscid water (material.model)",
    "periodic": "periodic axes (domain.periodic)",
    "apic": 'APIC transfers (solver.transfer = "apic"; it transfers by FLIP/PIC only)',
}


def _load():
    from . import explicit, projection  # noqa: F401  (they register themselves)


def supports(name, feature):
    """True when scheme ``name`` supports ``feature`` (a key of FEATURES)."""
    _load()
    return feature in SCHEMES[name].SUPPORTS


def supporting(feature):
    """The names of the schemes that support ``feature``."""
    _load()
    return [name for name, cls in SCHEMES.items() if feature in cls.SUPPORTS]


def register(name):
    def deco(cls):
        SCHEMES[name] = cls
        return cls

    return deco


def make_scheme(case, grid, particles):
    _load()
    return SCHEMES[case.solver.scheme](case, grid, particles)
