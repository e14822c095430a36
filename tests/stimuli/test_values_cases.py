"""Issue 28 cases 5-7: values inside the documented ranges that hung the build or
ended in a traceback or an error naming no file are refused when read, naming the
design (or style) file, the group (or key) and the allowed range or the physical
reason."""
import os
import re
import subprocess
import sys

import numpy as np
import pytest

from flipstudy.errors import FlipstudyError, StyleError
from flipstudy.render.style import Style
from flipstudy.stimuli import analyse, builtin
from flipstudy.stimuli.ballistic import MAX_FLIGHT_S, inject_kind, planned_flight
from flipstudy.stimuli.body import Body, BodyMappingError
from flipstudy.stimuli.design import DesignError, load_design
from flipstudy.stimuli.stimset import build_stimuli

BASE = """\
[study]
name = "t"
seed = 1

[[clips]]
name = "backflip"
source = "backflip"

[[groups]]
name = "g"
{group}
"""


def design(tmp_path, group: str):
    p = tmp_path / "design.toml"
    p.write_text(BASE.format(group=group))
    return p


def refused_when_read(tmp_path, group: str) -> tuple:
    """(design file, the DesignError's message) of a design refused by ``load_design``."""
    p = design(tmp_path, group)
    with pytest.raises(DesignError) as e:
        load_design(p)
    return p, str(e.value)


def style_refusal(tmp_path, key: str, value: str) -> tuple:
    """(style file, the StyleError's message) of a one-key style file."""
    p = tmp_path / "my.toml"
    p.write_text(f"[style]\n{key} = {value}\n")
    with pytest.raises(StyleError) as e:
        Style.from_toml(p)
    return p, str(e.value)


def build_in_subprocess(tmp_path, p):
    """``flipstudy stimuli`` of design ``p`` in a child with 1.5 GB of address space
    and 60 s: the cases that hung for minutes and ate 2.4 GB fail here on the old code."""
    limit = "import resource; resource.setrlimit(resource.RLIMIT_AS, (1_500_000_000,) * 2); "
    code = (limit + "import sys; from flipstudy.study.cli import main; "
            f"sys.exit(main(['stimuli', {str(p)!r}, '--out', {str(tmp_path / 'out')!r}]))")
    try:
        r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60,
                           env={**os.environ, "OMP_NUM_THREADS": "1"})
    except subprocess.TimeoutExpired:
        pytest.fail(f"{p}: the build of one stimulus ran for more than 60 s")
    assert r.returncode != 0
    assert "Traceback" not in r.stderr, r.stderr[-2000:]
    assert not (tmp_path / "out").exists()                 # nothing half-written
    return r.stderr


# ---------------------------------------------------------------- case 5: hangs
@pytest.mark.parametrize("group", [
    'kind = "acceleration"\naxis = "vertical"\nlevels = [99.99]',
    'kind = "gravity"\nsign = -1\npolicy = "takeoff-velocity"\nlevels = [99.99]',
    'kind = "gravity"\nsign = -1\npolicy = "apex-height"\nlevels = [99.99]',
    'kind = "time-scale"\nsign = -1\nspan = "whole"\nlevels = [99.99]',
])
def test_a_flight_that_nearly_never_lands_is_refused_before_the_build(tmp_path, group):
    p = design(tmp_path, group)
    err = build_in_subprocess(tmp_path, p)
    msg = err.strip().splitlines()[-1]
    assert str(p) in msg and "groups[0] (g)" in msg and "99.99 %" in msg and "'backflip'" in msg, msg
    m = re.search(r"the flight would last ([0-9.e+]+) s", msg)
    assert m and float(m.group(1)) > MAX_FLIGHT_S and f"within {MAX_FLIGHT_S:g} s" in msg, msg


def test_the_closed_form_flight_time_is_the_flight_of_the_built_stimulus():
    """The bound uses the flight time in closed form; the built stimulus's own COM
    (a parabola fitted to its airborne frames) comes back down to the landing
    height at that instant, and the stimulus holds that many seconds of frames."""
    from flipstudy.stimuli.physics import center_of_mass
    a = analyse(builtin("backflip"))
    t_to = a.takeoff_time
    y_land = a.path_at(np.array([a.landing_time]))[0][1]
    assert planned_flight(a, "horizontal-velocity", 0.5)[0] == pytest.approx(a.flight_s, abs=1e-12)
    for kind, error, option in [("acceleration", 0.5, "vertical"), ("gravity", -0.4, "takeoff-velocity"),
                                ("gravity", -0.4, "apex-height"), ("vertical-velocity", 0.3, None),
                                ("time-scale", -0.3, "flight"), ("gravity", 1.0, "takeoff-velocity")]:
        Tn, total = planned_flight(a, kind, error, option)
        stim = inject_kind(a, kind, error, option)
        fr = np.arange(stim.takeoff, stim.landing + 1)
        y = center_of_mass(stim.clip, a.body)[fr, 1]
        c2, c1, c0 = np.polyfit(fr / a.clip.fps - t_to, y, 2)
        land = max(np.roots([c2, c1, c0 - y_land]).real)      # the later root: touchdown
        assert land == pytest.approx(Tn, rel=1e-4), (kind, option, Tn, land)
        assert (stim.clip.num_frames - 1) / a.clip.fps == pytest.approx(total, abs=1.01 / a.clip.fps)


def test_a_long_but_landing_flight_is_still_built(tmp_path):
    """The bound is a bound, not a ban on slow flights: gravity −60 % (a 1.7 s flight) builds."""
    p = design(tmp_path, 'kind = "gravity"\nsign = -1\npolicy = "takeoff-velocity"\nlevels = [0, 60]')
    rows = build_stimuli(load_design(p), tmp_path / "out", progress=False).rows
    assert 1.5 < float(rows[-1]["flight_s"]) < MAX_FLIGHT_S
    # the flight it was built with is the closed form's (checked against the COM parabola above)
    planned = planned_flight(analyse(builtin("backflip")), "gravity", -0.6, "takeoff-velocity")[0]
    assert float(rows[-1]["flight_s"]) == pytest.approx(planned, abs=1.01 / 120)


# ------------------------------------------------------------ case 6: tracebacks
def test_a_grid_step_of_1e_308_is_a_design_error_naming_the_step(tmp_path):
    p, msg = refused_when_read(tmp_path, 'kind = "horizontal-velocity"\n'
                                         'levels = {from = 0, to = 100, step = 1e-308}')
    assert str(p) in msg and "groups[0] (g).levels.step" in msg and "at most 401" in msg, msg


def test_a_pose_rate_of_1e_9_is_a_design_error_naming_group_and_level(tmp_path):
    p = design(tmp_path, 'kind = "pose-rate"\nlevels = [1e-9]')
    with pytest.raises(DesignError) as e:
        build_stimuli(load_design(p), tmp_path / "out", progress=False).rows
    msg = str(e.value)
    assert str(p) in msg and "groups[0] (g)" in msg and "1e-09 poses per second" in msg, msg
    assert "no pose is shown inside" in msg
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("key, value, allowed", [
    ("trail_rate", "0", "more than 0 and at most 240"),
    ("ground_margin", "1e12", "from 0 to 100"),
    ("font_size", "nan", "more than 0 and at most 0.5"),
    ("ellipsoid_resolution", '"x"', "two numbers"),
    ("ellipsoid_resolution", "[3000, 3000]", "from 3 to 100"),
])
def test_a_style_value_that_took_minutes_is_refused_naming_file_and_key(tmp_path, key, value, allowed):
    p, msg = style_refusal(tmp_path, key, value)
    assert msg.startswith(f"{p}: [style] {key}: ") and allowed in msg, msg


# ------------------------------------------------------------ case 7: unclear errors
def test_angular_momentum_500_is_refused_when_read_naming_file_group_and_range(tmp_path):
    p, msg = refused_when_read(tmp_path, 'kind = "angular-momentum"\nprofile = "smooth"\nlevels = [500]')
    assert str(p) in msg and "groups[0] (g).levels" in msg and "below 500 %" in msg, msg
    p = design(tmp_path, 'kind = "angular-momentum"\nprofile = "abrupt"\nlevels = [0, 499]')
    p.write_text(p.read_text().replace("seed = 1", "seed = 1\ntolerance_pct = 5"))
    rows = build_stimuli(load_design(p), tmp_path / "out", progress=False).rows   # just below: built
    assert abs(float(rows[-1]["measured_error_pct"]) - 499) < 5


def test_a_skeleton_the_body_model_cannot_map_names_its_file(tmp_path):
    p = tmp_path / "stick.bvh"
    p.write_text("HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition "
                 "Zrotation Xrotation Yrotation\n JOINT Spine\n {\n  OFFSET 0 10 0\n  CHANNELS 3 "
                 "Zrotation Xrotation Yrotation\n  End Site\n  {\n   OFFSET 0 10 0\n  }\n }\n}\n"
                 "MOTION\nFrames: 2\nFrame Time: 0.0083333\n" + "0 90 0 0 0 0 0 0 0\n" * 2)
    from flipstudy import load_bvh
    clip = load_bvh(p, scale=0.01)
    with pytest.raises(BodyMappingError) as e:
        Body.from_clip(clip)
    assert str(e.value).startswith(f"{p}: cannot map the skeleton"), str(e.value)
    with pytest.raises(BodyMappingError, match=re.escape(str(p))):
        analyse(clip)


@pytest.mark.parametrize("key, value, allowed", [
    ("body_color", '"notacolor"', "not a colour"),
    ("ambient", "nan", "from 0 to 1"),
    ("marker_size", "-1", "more than 0 and at most 1"),
])
def test_a_style_value_accepted_silently_is_refused_naming_file_key_and_range(tmp_path, key, value,
                                                                               allowed):
    p, msg = style_refusal(tmp_path, key, value)
    assert issubclass(StyleError, FlipstudyError)
    assert msg.startswith(f"{p}: [style] {key}: ") and allowed in msg and value.strip('"') in msg, msg


def test_a_valid_style_renders_as_before_and_is_frozen():
    s = Style.from_dict({"body_color": [1.0, 0.0, 0.0], "ambient": 1, "ellipsoid_resolution": [8, 6]})
    assert s.body_color == (1.0, 0.0, 0.0) and s.ellipsoid_resolution == (8, 6)
    assert Style.from_dict(s.to_dict()) == s
    with pytest.raises(Exception):
        s.ambient = 0.5                                     # frozen
    d = Style()
    assert np.array_equal(d.ellipsoid_resolution, (20, 12)) and d.ground_margin == 4.0
