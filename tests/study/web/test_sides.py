"""Which tone is the left side: the instructions of the local runner and of the site
carry a sentence and a picture made from the style the videos were rendered in
(issue 42; the browser tests check that both pages show them)."""
import json

import pytest

from flipstudy.render.sides_figure import side_words
from flipstudy.render.style import Style
from flipstudy.study.demo import make_demo_study
from flipstudy.study.session import load_study
from flipstudy.study.web import sides
from flipstudy.study.web.site import site_config


@pytest.fixture
def study(tmp_path, monkeypatch):
    monkeypatch.setattr(sides, "_picture", lambda style: b"\x89PNG...")   # no render here
    return make_demo_study(tmp_path / "s", videos=False)


def _render_style(study, **style):
    (study / "render").mkdir(exist_ok=True)
    (study / "render" / "render.json").write_text(json.dumps({"style": Style(**style).to_dict()}))


def test_the_site_config_says_which_tone_is_left_with_a_picture(study):
    cfg = site_config(load_study(study))
    s = cfg["sides"]
    assert "left arm and leg are the lighter tone" in s["text"] and "right arm and leg" in s["text"]
    assert s["image"].startswith("data:image/png;base64,") and s["width"] == sides.WIDTH


def test_the_words_follow_the_rendered_style(study):
    _render_style(study, side_colors=("#3d6a9e", "#1a2f47", "#a9c4e6"))      # left darker
    assert "left arm and leg are the darker tone" in sides.sides_config(load_study(study))["text"]
    _render_style(study, sided=False)                                        # one tone: nothing to say
    assert sides.sides_config(load_study(study)) is None
    assert side_words(Style(sided=False)) is None
