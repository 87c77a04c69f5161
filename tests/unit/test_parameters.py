"""Unit tests of identification/parameters.py: the one table of parameter names, units and
groups (eq. 11, eq. 19, eq. 6 with q = qm)."""

from __future__ import annotations

import pytest

from jointbench.identification.parameters import (FRICTIONS, JOINT_MOTOR, MOTOR_ONLY,
                                                  MOTOR_ONLY_CORRECTED, MOTOR_ONLY_PHYSICAL,
                                                  PARAMETERS, RIGID, STIFFNESS_AND_INERTIAS,
                                                  TWO_MASS, units)


def test_model_vectors_follow_the_paper():
    # Eq. (11) in the regressor's column order, eq. (19), docs/cli.md's rigid model.
    assert JOINT_MOTOR == ("Jm", "FVm", "FSm", "K", "JL", "MX", "MY", "FV", "FS")
    assert MOTOR_ONLY == tuple(f"X{i}" for i in range(1, 8))
    assert MOTOR_ONLY_CORRECTED == tuple(f"X{i}" for i in range(1, 12))
    assert RIGID == ("J", "FV", "FS", "offset")


@pytest.mark.parametrize("group", [JOINT_MOTOR, RIGID, TWO_MASS, STIFFNESS_AND_INERTIAS,
                                   FRICTIONS, MOTOR_ONLY_PHYSICAL])
def test_every_physical_name_is_in_the_table(group):
    assert set(group) <= set(PARAMETERS)
    assert len(set(group)) == len(group)


def test_two_mass_is_the_joint_motor_vector_reordered():
    assert set(TWO_MASS) == set(JOINT_MOTOR)
    assert set(MOTOR_ONLY_PHYSICAL) <= set(TWO_MASS)


def test_the_table_is_keyed_by_name_with_known_groups():
    for name, p in PARAMETERS.items():
        assert p.name == name and p.what
        assert p.group in ("inertia", "stiffness", "friction", "gravity", "offset")
    assert {n for n, p in PARAMETERS.items() if p.group == "friction"} == set(FRICTIONS)


def test_revolute_units():
    u = units(prismatic=False)
    assert set(u) == set(PARAMETERS)
    assert u["K"] == "N m/rad" and u["Jm"] == u["JL"] == u["J"] == "kg m^2"
    assert u["FVm"] == u["FV"] == "N m s/rad" and u["FSm"] == u["FS"] == u["offset"] == "N m"
    assert u["MX"] == u["MY"] == "kg m"


def test_prismatic_units_replace_rad_and_n_m_by_m_and_n():
    u = units(prismatic=True)
    # Inertias become masses, torques forces, per radian per metre (log metadata
    # `axis: prismatic`, docs/log-format.md).
    assert u["K"] == "N/m" and u["Jm"] == u["JL"] == u["J"] == "kg"
    assert u["FVm"] == u["FV"] == "N s/m" and u["FSm"] == u["FS"] == u["offset"] == "N"
    for name, unit in u.items():
        assert "rad" not in unit and "m^2" not in unit, name
    assert PARAMETERS["K"].unit_for(True) == "N/m" and PARAMETERS["K"].unit_for(False) == "N m/rad"
