"""What each scheme supports, as data (issue 42): the case's rules read it without importing
the schemes, whose modules load the compiled core, and each scheme class takes its
``SUPPORTS`` from here (tests/schemes/test_capabilities.py checks that the registry and this
table name the same schemes)."""

from __future__ import annotations

# The features a scheme may support, as the case's rules name them to the user.
FEATURES = {
    "obstacles": "fixed obstacles ([[obstacles]])",
    "materials": "materials other than inviscid water (material.model)",
    "periodic": "periodic axes (domain.periodic)",
    "apic": 'APIC transfers (solver.transfer = "apic"; it transfers by FLIP/PIC only)',
    "outlets": 'outlets (domain.walls = "outlet")',
    "solids": 'solids (material.model = "elastic", "von_mises", "drucker_prager" or "poroelastic")',
    "bonded": 'bonded walls (domain.walls = "bonded")',
    "inlets": "inlets ([[inlets]])",
    "sponges": "damping zones ([[sponges]])",
    "loads": "surface loads ([[loads]])",
}

# solver.scheme -> the FEATURES it supports
SUPPORTS: dict[str, frozenset[str]] = {
    "projection": frozenset(
        {
            "obstacles",
            "materials",
            "periodic",
            "apic",
            "outlets",
            "solids",
            "bonded",
            "inlets",
            "sponges",
            "loads",
        }
    ),
    "explicit": frozenset(),
}


def supports(name: str, feature: str) -> bool:
    """True when scheme ``name`` supports ``feature`` (a key of FEATURES)."""
    return feature in SUPPORTS[name]


def supporting(feature: str) -> list[str]:
    """The names of the schemes that support ``feature``."""
    return [name for name, features in SUPPORTS.items() if feature in features]
