"""Issue 45's fuzzers of the readers (slow): ``.npy``, ``.npz``, layout files, AMASS
motions and body models, calibration files and ``[[sources]]`` designs, each drawn
case read in a worker subprocess limited to 2 GB of address space and 60 s a case
(tests/_support/_fuzz_worker.py).  Every case ends in a result or in one
:class:`~flipstudy.errors.FlipstudyError` line naming the file (or one of the
files) it read; none in a traceback, a MemoryError or the alarm.

The cases are seeded random mutations of valid files (truncations, flipped bytes,
rewritten ``.npy`` headers, drawn JSON/TOML values in every field) plus the
issue's named ones (a header of 10¹² frames, a sparse 10⁶-frame file, a 1 GB zip
of zeros, deep JSON, non-UTF-8 text).
"""
from __future__ import annotations

import copy
import json
import random
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from numpy.lib import format as npformat

from _bad_files import deep_json, npy_bytes, npy_header_only, zip_bomb, zip_of
from _positions import synthetic_body_model
from flipstudy import builtin
from flipstudy.stimuli.motion.positions import positions_of

pytestmark = pytest.mark.slow

WORKER = Path(__file__).resolve().parents[1] / "_support" / "_fuzz_worker.py"
N = 150                                   # random cases per reader


def run_cases(cases: list[dict]) -> list[dict]:
    """Every case through the worker (one process, 2 GB, 60 s a case); a worker that
    dies (killed by the limit) is restarted after the case it died on."""
    results, todo = [], list(cases)
    while todo:
        lines = "".join(json.dumps({**c, "id": i}) + "\n" for i, c in enumerate(todo))
        p = subprocess.run([sys.executable, str(WORKER)], input=lines, capture_output=True, text=True,
                           timeout=60 * len(todo) + 60)
        done = [json.loads(x) for x in p.stdout.splitlines() if x.startswith("{")]
        results += [{**r, "case": todo[r["id"]]} for r in done]
        if len(done) < len(todo):                            # the worker died on todo[len(done)]
            results.append({"status": "bug", "message": f"worker died (exit {p.returncode}): "
                            f"{p.stderr[-500:]}", "case": todo[len(done)]})
            todo = todo[len(done) + 1:]
        else:
            todo = []
    return results


def check(results: list[dict]) -> None:
    bugs = [r for r in results if r["status"] == "bug"]
    assert not bugs, f"{len(bugs)} tracebacks, the first: {bugs[0]['case']}\n{bugs[0]['message']}"
    for r in results:
        if r["status"] == "error":
            msg, names = r["message"], [Path(p).name for p in r["case"].get("files", [r["case"]["path"]])]
            assert "\n" not in msg, f"{r['case']}: a message of several lines: {msg!r}"
            assert any(n in msg for n in names), f"{r['case']}: {msg!r} names none of {names}"


# ---------------------------------------------------------------- drawn values
POOL = [None, True, 0, -1, 1, 2, 22, 30, 1e9, 1e300, -1e300, float("inf"), float("-inf"), float("nan"),
        "", "fast", "y", "z", "x", "a", "Hips", "é" * 3, "a b", "x" * 300, [], [1, 2], ["a"], [[["a"]]],
        {}, {"a": 1}, {"neck": ["b"]}]


def draw_value(rng: random.Random):
    return copy.deepcopy(rng.choice(POOL))


def mutate_bytes(rng: random.Random, raw: bytes) -> bytes:
    how = rng.randrange(4)
    if how == 0:
        return raw[:rng.randrange(len(raw) + 1)]
    b = bytearray(raw)
    if how == 1:
        for _ in range(rng.randint(1, 8)):
            b[rng.randrange(len(b))] = rng.randrange(256)
        return bytes(b)
    if how == 2:
        at = rng.randrange(min(len(b), 128))
        b[at:at] = bytes(rng.randrange(256) for _ in range(rng.randint(1, 16)))
        return bytes(b)
    return bytes(rng.randrange(256) for _ in range(rng.randint(0, 300)))


DESCRS = ["<f8", "<f4", "<f2", ">f8", "<i8", "|u1", "|b1", "<c16", "|O", "<U4", "|S3", "|V8", "<M8[s]"]
DIMS = [0, 1, 2, 3, 4, 22, 263, 10**6, 10**12, 2**62]


def drawn_npy(rng: random.Random, path: Path, base: np.ndarray) -> None:
    how = rng.randrange(3)
    if how == 0:
        path.write_bytes(mutate_bytes(rng, npy_bytes(base)))
        return
    shape = tuple(rng.choice(DIMS) for _ in range(rng.randrange(5)))
    with open(path, "wb") as f:
        npformat.write_array_header_1_0(f, {"descr": rng.choice(DESCRS), "fortran_order": rng.random() < 0.3,
                                            "shape": shape})
        f.write(bytes(rng.randrange(256) for _ in range(rng.choice([0, 7, 64, 2000]))))
    if how == 2:
        path.write_bytes(mutate_bytes(rng, path.read_bytes()))


def _positions() -> np.ndarray:
    X, _ = positions_of(builtin("jump"), tips=False)
    return X


def test_npy_files(tmp_path):
    rng, X = random.Random(45_12), _positions()
    cases = []
    for i in range(N):
        p = tmp_path / f"n{i}.npy"
        drawn_npy(rng, p, X[:, :22] if rng.random() < 0.5 else X)
        cases.append({"kind": "clip", "path": str(p)})
    named = {"frames12.npy": lambda p: npy_header_only(p, (10**12, 22, 3)),
             "sparse6.npy": lambda p: npy_header_only(p, (10**6, 22, 3), "<f4", sparse_data=True),
             "bvh.npy": lambda p: p.write_text("HIERARCHY\nROOT Hips\n{\n"),
             "empty.npy": lambda p: p.write_bytes(b"")}
    for name, write in named.items():
        write(tmp_path / name)
        cases.append({"kind": "clip", "path": str(tmp_path / name)})
    (tmp_path / "dir.npy").mkdir()
    cases.append({"kind": "clip", "path": str(tmp_path / "dir.npy")})
    check(run_cases(cases))


ARRAYS = [lambda rng, X: X, lambda rng, X: X[:, :22], lambda rng, X: X.astype(np.float32),
          lambda rng, X: X + 1j, lambda rng, X: np.array([{"a": 1}], dtype=object), lambda rng, X: np.array("fast"),
          lambda rng, X: np.array([30.0, 60.0]), lambda rng, X: np.float64(rng.choice([30, 0, -5, 1e9, np.nan])),
          lambda rng, X: np.zeros((2, 22, 3)), lambda rng, X: np.zeros(0), lambda rng, X: np.array(1 + 2j)]
MEMBERS = ["joints", "positions", "joint_positions", "fps", "mocap_framerate", "other"]


def test_npz_files(tmp_path):
    rng, X = random.Random(45_13), _positions()
    cases = []
    for i in range(N):
        p = tmp_path / f"z{i}.npz"
        members = {f"{rng.choice(MEMBERS)}.npy": rng.choice(ARRAYS)(rng, X) for _ in range(rng.randint(0, 3))}
        if rng.random() < 0.2:
            members["bad.npy"] = mutate_bytes(rng, npy_bytes(X))
        zip_of(p, members or {"readme.txt": b"x"}, compress=rng.random() < 0.5)
        if rng.random() < 0.4:
            p.write_bytes(mutate_bytes(rng, p.read_bytes()))
        cases.append({"kind": "clip", "path": str(p)})
    zip_bomb(tmp_path / "bomb.npz", (2_000, 1_000, 67))         # 1.07 GB of zeros in about 1 MB
    cases.append({"kind": "clip", "path": str(tmp_path / "bomb.npz")})
    check(run_cases(cases))


def _layout_table(rng: random.Random) -> dict:
    d = {"joints": [f"j{k}" for k in range(22)], "parents": [-1] + list(range(21)), "fps": 30}
    for key in rng.sample(["joints", "parents", "fps", "up", "scale", "landmarks", "extra"], rng.randint(1, 3)):
        if key == "parents" and rng.random() < 0.5:
            d[key] = [rng.choice([-1, 0, 5, 21, 22, "j0", "", None, 1.5]) for _ in range(22)]
        else:
            d[key] = draw_value(rng)
    return d


def test_layout_files(tmp_path):
    rng, X = random.Random(45_15), _positions()
    np.save(tmp_path / "m.npy", X[:, :22])
    cases = []
    for i in range(N):
        suffix = rng.choice([".json", ".json", ".toml"])
        p = tmp_path / f"l{i}{suffix}"
        d = _layout_table(rng)
        if suffix == ".json":
            text = json.dumps(d).encode()
        else:
            text = ("joints = " + json.dumps(d["joints"]) + "\nparents = " +
                    json.dumps([x if x is not None else "" for x in d["parents"]]
                               if isinstance(d["parents"], list) else 0) + "\n").encode()
        p.write_bytes(mutate_bytes(rng, text) if rng.random() < 0.3 else text)
        cases.append({"kind": "clip", "path": str(tmp_path / "m.npy"), "kwargs": {"layout": str(p)},
                      "files": [str(tmp_path / "m.npy"), str(p)]})
    for name, raw in (("deep.json", deep_json().encode()), ("utf.json", b'{"joints": ["\xff"]}'),
                      ("inf.json", b'{"joints": ["a", "b"], "parents": [-1, 0], "fps": Infinity}'),
                      ("deep.toml", b"a = " + b"[" * 50_000 + b"]" * 50_000)):
        (tmp_path / name).write_bytes(raw)
        cases.append({"kind": "clip", "path": str(tmp_path / "m.npy"), "kwargs": {"layout": str(tmp_path / name)},
                      "files": [str(tmp_path / "m.npy"), str(tmp_path / name)]})
    check(run_cases(cases))


def test_amass_motions_and_body_models(tmp_path):
    rng = random.Random(45_16)
    model, _ = synthetic_body_model()
    np.savez(tmp_path / "model.npz", **model)
    good = {"poses": np.zeros((30, 156)), "trans": np.zeros((30, 3)), "betas": np.zeros(10),
            "mocap_framerate": np.float64(60.0)}
    pool = [lambda a: a[:, :30] if a.ndim == 2 else a, lambda a: a + 1j, lambda a: a.astype(str),
            lambda a: np.full_like(a, np.nan, dtype=float), lambda a: np.array([None], dtype=object),
            lambda a: np.zeros((0,) + a.shape[1:]), lambda a: np.array([60.0, 120.0]), lambda a: a.reshape(-1),
            lambda a: np.float64(1e9), lambda a: a.T]
    cases = []
    for i in range(N):
        d = dict(good)
        m = dict(model)
        target = d if rng.random() < 0.5 else m
        for k in rng.sample(sorted(target), rng.randint(1, 2)):
            if rng.random() < 0.2:
                del target[k]
            else:
                target[k] = rng.choice(pool)(np.asarray(target[k]))
        mp, bp = tmp_path / f"a{i}.npz", tmp_path / f"b{i}.npz"
        zip_of(mp, {f"{k}.npy": v for k, v in d.items()})
        zip_of(bp, {f"{k}.npy": v for k, v in m.items()})
        if rng.random() < 0.2:
            bp.write_bytes(mutate_bytes(rng, bp.read_bytes()))
        cases.append({"kind": "clip", "path": str(mp), "kwargs": {"body_model": str(bp)},
                      "files": [str(mp), str(bp)]})
    (tmp_path / "text_model.npz").write_text("not a model")
    zip_of(tmp_path / "ok.npz", {f"{k}.npy": v for k, v in good.items()})
    cases.append({"kind": "clip", "path": str(tmp_path / "ok.npz"),
                  "kwargs": {"body_model": str(tmp_path / "text_model.npz")},
                  "files": [str(tmp_path / "ok.npz"), str(tmp_path / "text_model.npz")]})
    check(run_cases(cases))


def _leaves(d, path=()):
    if isinstance(d, dict):
        for k, v in d.items():
            yield from _leaves(v, path + (k,))
    elif isinstance(d, list) and d and len(d) < 50:
        for i, v in enumerate(d):
            yield from _leaves(v, path + (i,))
    else:
        yield path


def test_calibration_files(tmp_path):
    from flipstudy.stimuli.calibration import default_calibration
    rng = random.Random(45_14)
    good = default_calibration().to_dict()
    leaves = list(_leaves(good))
    cases = []
    for i in range(N):
        d = copy.deepcopy(good)
        for path in rng.sample(leaves, rng.randint(1, 3)):
            node = d
            for k in path[:-1]:
                node = node[k]
            if path:
                node[path[-1]] = draw_value(rng)
        p = tmp_path / f"c{i}.json"
        raw = json.dumps(d).encode()
        p.write_bytes(mutate_bytes(rng, raw) if rng.random() < 0.2 else raw)
        cases.append({"kind": "calibration", "path": str(p)})
    for name, raw in (("deep.json", ("[" * 100_000 + "]" * 100_000).encode()), ("utf.json", b'{"a": "\xff"}'),
                      ("src.json", json.dumps({**good, "sources": [1, "x"]}).encode())):
        (tmp_path / name).write_bytes(raw)
        cases.append({"kind": "calibration", "path": str(tmp_path / name)})
    check(run_cases(cases))


SOURCE_NAMES = ["gt", "a", "b", "m.1", "a b", "sprüng", "x" * 70, "", "reference", "gt-vs-a"]
FOLDERS = ["gt", "gt/", "gt/./", "./gt", "a", "b", "missing", "/", "a/../gt", "x" * 5000]
STEMS = ["88_01", "jump", "my clip", "sprüng", "x" * 200, ".hidden", "-dash"]


def test_sources_designs(tmp_path):
    """Drawn comparison designs, read and built: each a valid design (two or three
    sources of one or two items) with one or two fields drawn hostile: the number of
    sources (up to 1,000, compare = "all"), a folder written twice, a name, an item's
    file name, repetitions, compare, error levels, 2- and 3-frame clips."""
    from flipstudy import save_bvh
    from flipstudy.stimuli.motion.clip import Clip
    jump = builtin("jump")
    save_bvh(jump, tmp_path / "jump.bvh")
    clips = {"full": (tmp_path / "jump.bvh").read_bytes()}
    for n, at in ((2, 0), (3, 150), (2, 160)):                  # 2- and 3-frame clips, standing or in the air
        save_bvh(Clip(jump.skeleton, jump.fps, jump.root_pos[at:at + n], jump.rotations[at:at + n]),
                 tmp_path / "short.bvh")
        clips[f"{n}@{at}"] = (tmp_path / "short.bvh").read_bytes()
    rng = random.Random(45_1316)
    cases = []
    for i in range(N // 3):
        root = tmp_path / f"d{i}"
        hostile = set(rng.sample(["count", "folder", "name", "stem", "repetitions", "compare", "levels",
                                  "short"], rng.randint(1, 2)))
        clip = clips[rng.choice(sorted(clips))] if "short" in hostile else clips["full"]
        stems = rng.sample(STEMS if "stem" in hostile else STEMS[:2], rng.randint(1, 2))
        for f in ("gt", "a", "b"):
            (root / f).mkdir(parents=True)
            for stem in stems:
                (root / f / f"{stem}.bvh").write_bytes(clip)
        n = rng.choice([0, 1, 65, 200, 1000]) if "count" in hostile else rng.choice([2, 3])
        compare = rng.choice(["none", 3, "all"]) if "compare" in hostile or "count" in hostile \
            else rng.choice(["first", "all"])
        reps = rng.choice([0, 20, 21]) if "repetitions" in hostile else 1
        text = (f'[study]\nname = "f"\nseed = 1\ntask = "2afc"\nrepetitions = {reps}\n'
                f"compare = {json.dumps(compare)}\n")
        for k in range(n):
            name = rng.choice(SOURCE_NAMES) if "name" in hostile and k == n - 1 else f"s{k}"
            folder = ["gt", "a", "b"][k] if k < 3 else f"f{k}"
            if "folder" in hostile and k == 1:
                folder = rng.choice(FOLDERS)
            text += f"\n[[sources]]\nname = {json.dumps(name)}\nfolder = {json.dumps(folder)}\n"
        if "levels" in hostile:
            levels = sorted({0.0, *rng.sample([5.0, 10.0, 20.0, 99.999999, 1e9], rng.randint(1, 3))})
            text += f'\n[[groups]]\nname = "g"\nkind = "takeoff-angle"\nlevels = {json.dumps(levels)}\n'
        p = root / "design.toml"
        p.write_text(text)
        cases.append({"kind": "design", "path": str(p), "out": str(root / "study"), "files": [str(p), str(root)]})
    check(run_cases(cases))
