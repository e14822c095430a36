"""What ``render_study`` records about how it made the pixels and the videos
(the anti-aliasing actually run, the encoder), checked against the files, and
that a worker draws every output of every stimulus in its one scene."""
from __future__ import annotations

import json

from flipstudy.render.style import ANTI_ALIASING_METHODS
from flipstudy.render.study import render_study
from flipstudy.render.video import ENCODER
from test_render import _write_study, jumper


def test_render_json_records_the_anti_aliasing_and_the_encoder_the_files_show(tmp_path, monkeypatch):
    import flipstudy.render.scene as scene_mod
    built = []
    init = scene_mod.Scene.__init__

    def counted(self, *a, **k):
        built.append(1)
        init(self, *a, **k)
    monkeypatch.setattr(scene_mod.Scene, "__init__", counted)
    a, t0, t1 = jumper(flip=2.0)
    _write_study(tmp_path, [(f"s{k}", a, 0 if k == 0 else 10 * k) for k in range(2)], t0, t1)
    rec = render_study(tmp_path, what=["video", "ghost", "trail"], size=(64, 48), fps=10.0, jobs=1,
                       progress=False)
    assert rec.made == 6
    assert len(built) == 1            # videos, ghosts and trails of both in one scene
    on_disk = json.loads((tmp_path / "render" / "render.json").read_text())
    assert on_disk["anti_aliasing"] == {"style": "fxaa", "method": ANTI_ALIASING_METHODS["fxaa"]}
    assert on_disk["encoder"] == ENCODER and ENCODER["preset"] == "veryfast"
    settings = on_disk["settings_records"][on_disk["settings_id"]]
    assert settings["anti_aliasing"] == on_disk["anti_aliasing"] and settings["encoder"] == ENCODER
    # x264 writes its options into the stream: veryfast is subme=2 with one reference frame
    # (medium, the preset before, is subme=7 ref=3)
    data = (tmp_path / "render" / "s1.mp4").read_bytes()
    assert b"subme=2" in data and b" ref=1 " in data and b"crf=18.0" in data
