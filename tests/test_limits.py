"""``AxisLimits``: construction, defaults, validation messages, helpers."""

from __future__ import annotations

import dataclasses
import math

import pytest

from trajkit import AxisLimits, InvalidInputError


def test_decel_defaults_to_accel_leg():
    lim = AxisLimits(1.0, 2.0, 10.0)
    assert lim.a_max_decel == 2.0 and lim.j_max_decel == 10.0
    assert lim.symmetric
    assert lim.position_min == -math.inf and lim.position_max == math.inf
    asym = AxisLimits(1, 2, 10, a_max_decel=3)
    assert asym.a_max_decel == 3.0 and asym.j_max_decel == 10.0 and not asym.symmetric
    assert isinstance(asym.v_max, float)


def test_frozen_and_name_not_compared():
    lim = AxisLimits(1.0, 2.0, 10.0, name="A")
    with pytest.raises(dataclasses.FrozenInstanceError):
        lim.v_max = 3.0
    assert lim == AxisLimits(1.0, 2.0, 10.0, name="B")
    assert lim.with_name("C").name == "C" and lim.with_name("C") == lim


def test_infinite_limits_allowed_where_meaningful():
    assert AxisLimits(math.inf, 2.0, 10.0).v_max == math.inf
    assert AxisLimits(1.0, math.inf, 10.0).a_max == math.inf
    trap = AxisLimits(1.0, 2.0, math.inf)
    assert trap.j_max == trap.j_max_decel == math.inf


def test_scaled_converts_units():
    deg = AxisLimits(180.0, 360.0, 3600.0, 720.0, 1800.0, -90.0, 270.0, name="A")
    rad = deg.scaled(math.pi / 180.0)
    assert rad.v_max == pytest.approx(math.pi)
    assert rad.a_max_decel == pytest.approx(4 * math.pi)
    assert rad.j_max_decel == pytest.approx(10 * math.pi)
    assert (rad.position_min, rad.position_max) == pytest.approx((-math.pi / 2, 1.5 * math.pi))
    assert rad.name == "A"
    with pytest.raises(InvalidInputError, match=r"scale factor should be larger than zero, got -1\.0"):
        deg.scaled(-1.0)


def test_check_position():
    lim = AxisLimits(1.0, 1.0, 1.0, position_min=-1.0, position_max=2.0, name="Z")
    assert lim.check_position(2.0) == 2.0
    with pytest.raises(InvalidInputError,
                       match=r"^goal 2\.5 of axis Z is outside the position range \[-1\.0, 2\.0\]$"):
        lim.check_position(2.5, "goal")
    with pytest.raises(InvalidInputError, match=r"^start of axis Z must be finite, got nan$"):
        lim.check_position(math.nan, "start")


@pytest.mark.parametrize("kwargs,match", [
    (dict(v_max=0.0), r"^maximum velocity limit v_max of axis 2 should be larger than zero, got 0\.0$"),
    (dict(v_max=-1.0), r"^maximum velocity limit v_max of axis 2 should be larger than zero, got -1\.0$"),
    (dict(v_max=math.nan), r"^maximum velocity limit v_max of axis 2 must be a number, got nan$"),
    (dict(a_max=-math.inf),
     r"^maximum acceleration limit a_max of axis 2 must be finite and larger than zero, got -inf$"),
    (dict(j_max="fast"), r"^maximum jerk limit j_max of axis 2 must be a number, got 'fast'$"),
    (dict(a_max_decel=0.0),
     r"^maximum deceleration limit a_max_decel of axis 2 should be larger than zero, got 0\.0$"),
    (dict(j_max_decel=math.nan),
     r"^maximum deceleration jerk limit j_max_decel of axis 2 must be a number, got nan$"),
    (dict(a_max=math.inf, j_max=math.inf),
     r"^a_max and j_max of axis 2 cannot both be infinite \(the velocity would jump\)$"),
    (dict(a_max_decel=math.inf, j_max_decel=math.inf),
     r"^a_max_decel and j_max_decel of axis 2 cannot both be infinite"),
    (dict(position_min=3.0, position_max=1.0), r"^position_min 3\.0 is above position_max 1\.0 of axis 2$"),
    (dict(position_min=math.nan), r"^position range of axis 2 must not be NaN, got \[nan, inf\]$"),
    (dict(position_min=math.inf), r"^position range of axis 2 is empty: \[inf, inf\]$"),
    (dict(position_max="x"), r"^position range of axis 2 must be numbers"),
])
def test_invalid_limits_messages(kwargs, match):
    args = dict(v_max=1.0, a_max=2.0, j_max=10.0, name=2)
    args.update(kwargs)
    with pytest.raises(InvalidInputError, match=match):
        AxisLimits(**args)


def test_invalid_limits_is_a_value_error():
    with pytest.raises(ValueError, match=r"should be larger than zero, got -2\.0"):
        AxisLimits(1.0, -2.0, 1.0)


def test_derated_scales_both_legs_and_keeps_range_and_name():
    lm = AxisLimits(1.0, 4.0, 40.0, a_max_decel=6.0, j_max_decel=60.0,
                    position_min=-1.0, position_max=2.0, name="B")
    d = lm.derated(accel=0.5, jerk=0.25)
    assert (d.v_max, d.a_max, d.a_max_decel, d.j_max, d.j_max_decel) == (1.0, 2.0, 3.0, 10.0, 15.0)
    assert (d.position_min, d.position_max, d.name) == (-1.0, 2.0, "B")
    assert lm.derated() == lm and lm.derated(velocity=0.5).v_max == 0.5


@pytest.mark.parametrize("kw, pattern", [
    ({"accel": 0.0}, r"derating factor accel of axis B must be in \(0, 1\], got 0\.0"),
    ({"jerk": 1.5}, r"derating factor jerk of axis B must be in \(0, 1\], got 1\.5"),
    ({"velocity": float("nan")}, r"derating factor velocity of axis B .*nan"),
    ({"accel": "x"}, r"derating factor accel of axis B must be a number"),
])
def test_derated_rejects_bad_factors(kw, pattern):
    with pytest.raises(InvalidInputError, match=pattern):
        AxisLimits(1.0, 4.0, 40.0, name="B").derated(**kw)
