"""A drape's set-up is one DrapeSettings: resolved once from a scene, carried through the
engine's stages and recorded from the same object (issue 31)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import preform
from preform.base import fidelity
from preform.drape import NodeStatus, PlyOutline, drape
from preform.drape.engine.net import place_fronts, place_generators, place_start
from preform.drape.engine.settings import DrapeError, DrapeSettings
from preform.drape.steps import drape_settings, run_drape
from preform.plugins.surfaces.basic import Hemisphere
from preform.step import CaseContext

HEMI = Hemisphere(0.1)
PLY = PlyOutline.rectangle((0.16, 0.16))


def _same_net(a, b) -> None:
    assert np.array_equal(a.status, b.status)
    assert np.array_equal(a.nodes, b.nodes, equal_nan=True)
    assert (a.generator_angle, a.orientation) == (b.generator_angle, b.orientation)


@settings(max_examples=8, deadline=None)
@given(
    angle=st.floats(math.radians(40), math.radians(140)),
    orientation=st.floats(-math.pi, math.pi),
)
def test_settings_keywords_and_overrides_give_the_same_net(angle, orientation):
    by_hand = drape(
        HEMI, node_spacing_m=0.01, ply=PLY, start_xy_m=(0.01, -0.02),
        generator_angle_rad=angle, orientation_rad=orientation,
    )  # fmt: skip
    base = DrapeSettings(node_spacing_m=0.01, ply=PLY, start_xy_m=(0.01, -0.02))
    _same_net(by_hand, drape(HEMI, dataclasses.replace(base, generator_angle_rad=angle,
                                                       orientation_rad=orientation)))  # fmt: skip
    # keywords replace the settings' own fields; keywords() round-trips
    overridden = drape(HEMI, base, generator_angle_rad=angle, orientation_rad=orientation)
    _same_net(by_hand, overridden)
    moved = dataclasses.replace(base, generator_angle_rad=angle, orientation_rad=orientation)
    _same_net(by_hand, drape(HEMI, **moved.keywords()))


def test_the_stages_compose_to_drape():
    s = DrapeSettings(node_spacing_m=0.01, ply=PLY, start_xy_m=(0.0, 0.0))
    start = place_start(HEMI, s)
    # the start lies on the sphere and the generators leave at α in its tangent plane
    assert np.linalg.norm(start.point) == pytest.approx(0.1, abs=1e-12)
    assert math.acos(float(start.t_u @ start.t_v)) == pytest.approx(s.generator_angle_rad)
    net = place_generators(HEMI, s, start)
    placed_before = int(np.count_nonzero(net.status == NodeStatus.PLACED))
    fronts = place_fronts(HEMI, s, net)
    assert fronts.placement == "closed form" and fronts.fronts > 0
    assert np.count_nonzero(net.status == NodeStatus.PLACED) > placed_before
    whole = drape(HEMI, s)
    assert np.array_equal(whole.nodes.reshape(-1, 3), net.pos, equal_nan=True)


@pytest.mark.parametrize(
    ("field", "value", "says"),
    [("node_spacing_m", 0.0, "positive length"), ("node_spacing_m", math.nan, "positive length"),
     ("tolerance", 0.1, "relative")],
)  # fmt: skip
def test_a_set_up_that_gives_no_net_is_refused_where_it_is_made(field, value, says):
    with pytest.raises(DrapeError, match=says):
        DrapeSettings(**{"node_spacing_m": 0.01, "ply": PLY, field: value})


def test_the_drape_step_resolves_the_knobs_once_and_records_those(tmp_path, monkeypatch):
    d = preform.drape("plain-weave-150", node_spacing_mm=5, generator_angle_deg=80)
    ctx = CaseContext(d.fabric, d.scene, preform.default_host().registry, tmp_path)
    ctx.products.update({k: v for k, v in d.products.items() if k != "drape"})
    made = drape_settings(ctx.scene, ctx.products["surface"])
    resolved = []
    real = fidelity.resolve

    def counting(*args, **kwargs):
        resolved.append(real(*args, **kwargs))
        return resolved[-1]

    monkeypatch.setattr(fidelity, "resolve", counting)
    ply = run_drape(ctx)["drape"]
    assert len(resolved) == 1
    knobs = resolved[0]
    assert knobs == made.fidelity
    for key, value in knobs.as_dict().items():
        assert ctx.summary[key if key == "fidelity" else f"knob_{key}"] == value
    assert ply.result.node_spacing == pytest.approx(knobs.node_spacing_mm * 1e-3)
    assert ply.result.info["tolerance_m"] == pytest.approx(
        knobs.solver_tolerance * knobs.node_spacing_mm * 1e-3
    )
