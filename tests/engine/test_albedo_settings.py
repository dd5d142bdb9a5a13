"""Albedo settings are checked once (issue 40 item 3): :func:`brdfnorm.engine.methods.check_settings` serves both
:func:`brdfnorm.albedo` and a table job's :class:`brdfnorm.parallel.job.AlbedoSettings`, so a job refuses in the
calling process exactly what ``albedo`` would refuse in a worker — the same message, naming the same argument."""

from __future__ import annotations

import pytest

import brdfnorm as bn
from brdfnorm.errors import ArgumentError, ArgumentTypeError
from brdfnorm.parallel.job import AlbedoSettings

BAD = [
    ("lambert", {"rtol": -1.0}),
    ("lambert", {"rtol": 0.0, "atol": 0.0}),
    ("lambert", {"max_evaluations": 0}),
    ("lambert", {"nonfinite": "ignore"}),
    ("lambert", {"over": "both"}),
    ("lambert", {"method": "simpson"}),
    ("lambert", {"method": "series"}),  # does not apply
    ("lambert", {"digits": 20}),  # certified only
    ("ggx-dielectric", {"over": "view"}),  # a BSDF over the view (the job's own checks used to miss it)
]


def _refusal(call) -> tuple[type, str, str | None]:
    with pytest.raises((ArgumentError, ArgumentTypeError)) as caught:
        call()
    return type(caught.value), str(caught.value), getattr(caught.value, "where", None)


@pytest.mark.parametrize(("name", "settings"), BAD)
def test_a_job_refuses_what_albedo_refuses_with_the_same_message(name, settings):
    model = bn.load(name)
    direct = _refusal(lambda: bn.albedo(model, 0.3, **settings))
    job = _refusal(lambda: AlbedoSettings(**settings).validate(model))
    assert job == direct
    assert direct[2] is not None and direct[2] in {*settings, "rtol", "atol"}


def test_good_settings_pass_both():
    model = bn.load("phong", n=7.0)
    AlbedoSettings(method="certified", digits=20).validate(model)
    AlbedoSettings(rtol=1e-6, over="view", nonfinite="zero", max_evaluations=10_000).validate(model)
