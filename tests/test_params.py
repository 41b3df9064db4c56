"""Parameters (Eq. (19)): validation names the field; SI conversion of the Texier-Dorbolo pipe."""

from __future__ import annotations

import math

import pytest

from fempipe import Params, PipeSI
from fempipe.core.errors import ParamError

#: Texier & Dorbolo's pipe as given in the paper, Section 3.1 (Fig. 2b), with g = 9.8 m/s^2.
TD = {"L": 0.094, "EI": 1.8e-5, "m": 0.0159, "M": 0.0058, "g": 9.8}


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"alpha": math.nan}, "alpha"),
        ({"alpha": math.inf}, "alpha"),
        ({"beta": math.nan}, "beta"),
        ({"gamma": -math.inf}, "gamma"),
        ({"mu": math.nan}, "mu"),
        ({"v": math.inf}, "v"),
        ({"beta": 1.5}, "beta"),
        ({"beta": -0.1}, "beta"),
        ({"gamma": -1.0}, "gamma"),
        ({"mu": -1e-3}, "mu"),
        ({"v": -0.5}, "v"),
        ({"gamma": "abc"}, "gamma"),
    ],
)
def test_params_rejects_bad_values_naming_the_field(kwargs, field):
    with pytest.raises(ValueError, match=rf"^{field} ") as info:
        Params(**kwargs)
    assert isinstance(info.value, ParamError) and info.value.field == field


def test_negative_gravity_says_a_standing_pipe_is_alpha_pi():
    """gamma = (m+M) g L^3/EI is a magnitude: "upwards" gravity is the inclination alpha = pi."""
    with pytest.raises(ParamError, match=r"standing up is alpha = pi with gamma > 0") as info:
        Params(gamma=-10.0)
    assert info.value.field == "gamma"


@pytest.mark.parametrize("beta", [0.0, 1.0])
def test_params_accepts_the_ends_of_the_beta_range(beta):
    assert Params(beta=beta).beta == beta


@pytest.mark.parametrize(
    "change, field",
    [
        ({"L": 0.0}, "L"),
        ({"EI": -1.0}, "EI"),
        ({"m": -0.01}, "m"),
        ({"M": math.nan}, "M"),
        ({"g": -9.8}, "g"),
        ({"a": -1.0}, "a"),
        ({"m": 0.0, "M": 0.0}, "m \\+ M"),
    ],
)
def test_pipe_si_rejects_bad_values_naming_the_field(change, field):
    with pytest.raises(ValueError, match=rf"^{field}") as info:
        PipeSI(**{**TD, **change})
    assert isinstance(info.value, ParamError) and info.value.field == field.split()[0]


@pytest.mark.parametrize("change", [{"L": 1e200}, {"EI": 1e-320}, {"a": 1.0, "L": 1e-200}])
def test_pipe_si_whose_groups_overflow_is_refused(change):
    """L^3 of a float raises OverflowError (L^2 of a tiny one gives 0): refuse the pipe."""
    with pytest.raises(ParamError, match="overflows"):
        PipeSI(**{**TD, **change}).params()


def test_flow_velocity_that_overflows_is_refused():
    with pytest.raises(ParamError, match="overflows") as info:
        PipeSI(**TD).v_of_U(1e308)
    assert info.value.field == "U"


@pytest.mark.parametrize("U", [-1.0, math.nan])
def test_negative_or_nan_flow_velocity_is_rejected(U):
    with pytest.raises(ValueError, match="^U "):
        PipeSI(**TD).v_of_U(U)


def test_texier_dorbolo_conversion_matches_the_paper():
    """The paper (Section 3.1) quotes beta = 0.2673, gamma = 9.8129, v = 1.6874 U.

    Tolerance: half a unit of the last digit quoted, i.e. the values must round
    to the paper's.
    """
    pipe = PipeSI(alpha=math.pi / 2, **TD)
    p = pipe.params(U=1.0)
    assert abs(p.beta - 0.2673) <= 0.5e-4
    assert abs(p.gamma - 9.8129) <= 0.5e-4
    assert abs(p.v - 1.6874) <= 0.5e-4
    assert abs(pipe.v_of_U(2.0) / 2.0 - 1.6874) <= 0.5e-4
    assert p.alpha == pipe.alpha
    assert p.mu == 0.0  # a = 0: no Kelvin-Voigt damping


@pytest.mark.parametrize("U", [0.0, 0.37, 1.0, 3.0, 12.5])
def test_flow_velocity_round_trip(U):
    pipe = PipeSI(**TD)
    # Two floating-point operations each way: a few ulp.
    assert pipe.U_of_v(pipe.v_of_U(U)) == pytest.approx(U, rel=4e-16, abs=0)


def test_damping_is_the_retardation_time_in_units_of_the_time_scale():
    """Eq. (19): tau = t / T with T = L^2 sqrt((m+M)/EI), so mu = a / T."""
    a = 2.5e-3
    pipe = PipeSI(a=a, **TD)
    assert pipe.params().mu * pipe.time_scale == pytest.approx(a, rel=1e-14)


def test_dimensionless_groups_are_invariant_under_similarity():
    """Scaling m, M and EI by the same factor leaves beta, gamma and v(U) unchanged
    (all three are ratios of masses to stiffness), a check independent of the formulas'
    numerical values."""
    p1 = PipeSI(**TD).params(U=1.3)
    p2 = PipeSI(**{**TD, "m": 3 * TD["m"], "M": 3 * TD["M"], "EI": 3 * TD["EI"]}).params(U=1.3)
    for name in ("beta", "gamma", "v"):
        assert getattr(p2, name) == pytest.approx(getattr(p1, name), rel=1e-14)


def test_with_flow_returns_a_modified_copy():
    p = Params(alpha=1.0)
    q = p.with_flow(3.0)
    assert (p.v, q.v, q.alpha) == (0.0, 3.0, 1.0)
    assert q.to_dict() == {
        "alpha": 1.0,
        "beta": 0.142,
        "gamma": 18.9,
        "mu": 5e-3,
        "v": 3.0,
        "end_mass": 0.0,
        "external_damping": 0.0,
        "hysteretic_damping": 0.0,
        "springs": [],
    }
