"""Infinite numbers in port literals, against BT.CPP 4.8.2's ``convertFromString<double>``
(``std::stod``), read here through SetBlackboard writing text into a double entry.

A float port whose rule takes an infinity (``Accepts(also=(math.inf, ...))``) reads every
spelling of it BT.CPP reads, to the same value; other float ports keep refusing non-finite
numbers (a deliberate difference, docs/btcpp-differences.md), and both refuse a number beyond a
double's range.
"""

from __future__ import annotations

import math

import pytest
from btcpp_reference import run_btcpp

from bt_manip.bt.ports import Accepts, Port, convert_literal, takes_infinity, value_problem

EITHER_INFINITY = Port(float, False, "a bound", math.inf, Accepts(also=(math.inf, -math.inf)))
FINITE = Port(float, False, "a length", 1.0, Accepts(low=0))
SPELLINGS = ["inf", "INF", "Inf", "infinity", "Infinity", "INFINITY", "+inf", "-inf",
             "-Infinity", " inf", "inf "]


def btcpp_double(text: str) -> float | None:
    """The double BT.CPP converts ``text`` to, None when it refuses it."""
    statuses, values = run_btcpp(f'<SetBlackboard output_key="x" value="{text}"/>', 1,
                                 {"x": 0.5})
    return float(values["x"]) if statuses == ["SUCCESS"] else None


def port_value(info: Port, text: str) -> float | None:
    """The value bt-manip's port ``info`` takes for the literal ``text``, None when refused."""
    try:
        value = convert_literal(text, float, takes_infinity(info))
    except ValueError:
        return None
    return None if value_problem(info, value, text) is not None else value


@pytest.mark.parametrize("text", SPELLINGS)
def test_a_port_that_takes_infinity_reads_it_as_btcpp_does(text: str) -> None:
    expected = btcpp_double(text)
    assert expected is not None and math.isinf(expected)
    assert port_value(EITHER_INFINITY, text) == expected
    assert port_value(FINITE, text) is None  # a port without the rule refuses it


@pytest.mark.parametrize("text", ["1e999", "-1e999"])
def test_a_number_beyond_a_doubles_range_is_refused_by_both(text: str) -> None:
    assert btcpp_double(text) is None
    assert port_value(EITHER_INFINITY, text) is None


def test_nan_is_refused_even_where_infinity_is_taken() -> None:
    taken = btcpp_double("nan")
    assert taken is not None and math.isnan(taken)  # BT.CPP takes it
    assert port_value(EITHER_INFINITY, "nan") is None
    assert value_problem(EITHER_INFINITY, math.nan) == "must be a finite number, got nan"


def test_the_rule_text_names_infinity() -> None:
    assert value_problem(Port(float, False, "", 1.0, Accepts(low=0, also=(math.inf,))),
                         -math.inf, "-inf") == "must be >= 0 or inf, got -inf"
