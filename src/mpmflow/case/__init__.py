"""Case files: a TOML document validated against the schema (SI units throughout).

The schema is the single source of the case-file reference: every key's description is what
the documentation and the error messages show. One module per concern:

- ``sections``: one pydantic model per [table] (domain, grid, material, time, output,
  solver, probes, ...);
- ``domain``: the [domain] table (size, walls, periodic axes);
- ``solver``: the [solver] table (scheme, formulation, solvers);
- ``shapes``: the shapes of bodies and obstacles ([[bodies]], [[obstacles]]);
- ``model``: the whole case (``Case``) and the rules between its sections;
- ``loading``: reading the TOML file, ``--set`` overrides, messages that name the key;
- ``probe_data``: a probe's measured series (probes.N.data), read and checked;
- ``reference``: the key reference generated from the schema (docs/reference.md,
  ``mpmflow keys``).
"""

from .loading import (
    LIST_KEYS,
    apply_overrides,
    load_case,
    resolved,
    revalidate,
    validate,
    validate_case,
)
from .model import Case
from .reference import KNOWN_KEYS, key_reference, reference_markdown, reference_page
from .sections import COURANT, MAX_DT, MAX_STEPS

__all__ = [
    "COURANT",
    "KNOWN_KEYS",
    "LIST_KEYS",
    "MAX_DT",
    "MAX_STEPS",
    "Case",
    "apply_overrides",
    "key_reference",
    "load_case",
    "reference_markdown",
    "reference_page",
    "resolved",
    "revalidate",
    "validate",
    "validate_case",
]
