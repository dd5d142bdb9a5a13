"""brdfnorm.output.formats: the one value formatter, the format registry, and results that describe themselves
(Records) — checked against the results' own arrays and against formulas, not against the formatter itself."""

from __future__ import annotations

import csv
import io
import json

import numpy as np
import pytest

import brdfnorm as bn
from brdfnorm.errors import ArgumentError, ArgumentTypeError
from brdfnorm.output.formats import FORMATS, degrees, format_value, render, validate_format
from brdfnorm.registry import Registry


@pytest.mark.parametrize("value, digits, text", [
    (True, None, "1"), (np.bool_(False), 6, "0"), (3, None, "3"), (np.int64(7), 4, "7"),
    (0.1, None, "0.1"), (1 / 3, None, "0.3333333333333333"), (1 / 3, 6, "0.333333"), (2e307, 3, "2e+307"),
    ((0.5, 0.25, 1.0), 6, "0.5,0.25,1"), (np.array([1.0, 2.5]), None, "1.0,2.5"), ("quadrature", 3, "quadrature"),
])
def test_format_value(value, digits, text):
    assert format_value(value, digits) == text


def test_degrees_round_trip_what_the_command_line_gave():
    assert [degrees(np.radians(d)) for d in (0, 20, 60, 89.9)] == [0.0, 20.0, 60.0, 89.9]


def test_registry_validation_names_the_argument():
    assert set(FORMATS) == {"table", "json", "csv"} and validate_format("csv").name == "csv"
    with pytest.raises(ArgumentError, match="^format: unknown format 'xml' .known: table, json, csv."):
        validate_format("xml")
    with pytest.raises(ArgumentTypeError):
        validate_format(["json"])
    registry = Registry("thing", "thing", {"a": 1})
    with pytest.raises(ValueError, match="registered already"):
        registry.register("a", 2)


@pytest.fixture(scope="module")
def swept():
    model = bn.load("phong")
    return bn.normalize(model, sweep={"n": [1.0, 10.0, 100.0]}, at="normal", rtol=1e-11)


def test_normalization_records_in_every_format(swept):
    records = swept.records()
    data = json.loads(render(records, "json"))
    assert data["model"] == "phong" and data["at"] == "normal"
    rows = list(csv.DictReader(io.StringIO(render(records, "csv"))))
    for row, entry, n in zip(rows, data["results"], (1.0, 10.0, 100.0), strict=True):
        exact = (n + 1) / (2 * np.pi)  # seed 000: the original Phong lobe's factor at normal incidence
        assert float(row["n"]) == n and entry["params"]["n"] == n
        assert float(row["factor"]) == pytest.approx(exact, rel=1e-9) and entry["factor"] == float(row["factor"])
    table = render(records, "table")
    assert f"{swept.factor[2, 0, 0]:.12g}" in table and "normalization factor" in table


def test_progress_callback_reports_and_changes_no_number(swept):
    calls = []
    again = bn.normalize(bn.load("phong"), sweep={"n": [1.0, 10.0, 100.0]}, at="normal", rtol=1e-11,
                         on_progress=lambda done, total: calls.append((done, total)))
    assert calls[0] == (0, 3) and calls[-1] == (3, 3) and [d for d, _ in calls] == sorted(d for d, _ in calls)
    np.testing.assert_array_equal(again.factor, swept.factor)
    np.testing.assert_array_equal(again.values, swept.values)
    assert again.records().rows == swept.records().rows


def test_albedo_records_carry_the_model_and_tolerance():
    result = bn.albedo(bn.load("lambert", reflectance=0.5), np.radians([0.0, 60.0]), rtol=1e-9)
    records = result.records()
    assert records.meta == {"model": "lambert", "params": {"reflectance": 0.5}, "over": "light", "rtol": 1e-9}
    assert [r["theta_deg"] for r in records.rows] == [0.0, 60.0]
    assert [r["albedo"] for r in records.rows] == pytest.approx([0.5, 0.5], rel=1e-9)
