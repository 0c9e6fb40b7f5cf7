"""What each scheme supports is data the case reads (case.capabilities): the table, the
registry of scheme classes and the schema's choices of solver.scheme name the same schemes,
and each class supports what the table says."""

import typing

from mpmflow import schemes
from mpmflow.case import capabilities
from mpmflow.case.solver import Solver


def test_the_table_the_registry_and_the_schema_name_the_same_schemes():
    choices = set(typing.get_args(Solver.model_fields["scheme"].annotation))
    assert set(capabilities.SUPPORTS) == set(schemes.registry()) == choices


def test_each_scheme_supports_what_the_table_says():
    for name, cls in schemes.registry().items():
        assert cls.SUPPORTS == capabilities.SUPPORTS[name]
        assert cls.SUPPORTS <= set(capabilities.FEATURES)
    assert capabilities.supporting("apic") == ["projection"]
    assert not capabilities.supports("explicit", "obstacles")
