"""Reading and checking response tables (the long format of DESIGN.md)."""
from __future__ import annotations

from flipstudy.errors import NeedsExportError, ResponsesError
from pathlib import Path

import numpy as np
import pandas as pd

from flipstudy.vocab import answers, groupkeys
from flipstudy.vocab.design import SHARED_ORIGINAL_GROUP

REQUIRED = ("participant", "group", "level", "response")
#: DESIGN.md's long format, as the answer record declares it (flipstudy.vocab.answers)
DESIGN_COLUMNS = answers.DESIGN_COLUMNS
#: display order of the default design's groups; other names follow in order of appearance
DEFAULT_GROUP_ORDER = ("smooth-increase", "smooth-decrease", "abrupt-increase",
                       "abrupt-decrease", "takeoff-increase")
IGNORED_GROUPS = ("reference",)
#: the group of the shared originals (the design's, flipstudy.vocab.design)
SHARED_ORIGINAL = SHARED_ORIGINAL_GROUP
EXPORT_HINT = "flipstudy export {d} --out {d}/responses.csv"
#: the values of the optional columns ``task`` and ``method`` (missing: yes-no, constant):
#: the design's (flipstudy.vocab.groupkeys)
TASKS = groupkeys.TASKS
METHODS = groupkeys.METHODS


def resolve_responses_path(path: str | Path) -> Path:
    """A responses CSV, or a study folder holding ``responses.csv``."""
    p = Path(path)
    if p.is_dir():
        csv = p / "responses.csv"
        if csv.is_file():
            return csv
        raise NeedsExportError(
            f"{p} is a study folder without responses.csv: run "
            f"`{EXPORT_HINT.format(d=p)}` first, then `flipstudy analyze {p}`")
    if not p.exists():
        raise ResponsesError(f"{p}: no such file or folder (expected a responses CSV or a study folder)")
    return p


def load_responses(source, *, name: str | None = None, catch_groups=()) -> pd.DataFrame:
    """Read and check a response table.

    ``source`` is a DataFrame, a CSV path, or a study folder (its
    ``responses.csv``).  Returns a new DataFrame with the checked columns:
    ``participant`` (str), ``group`` (str), ``level`` (float, nominal error in
    percent), ``response`` (``"correct"``/``"incorrect"``; 2AFC rows:
    ``"first"``/``"second"``), ``incorrect`` (0/1; 0 on 2AFC rows), ``detected``
    (0/1: yes/no answered "incorrect", 2AFC chose the original as the physically
    correct one, by column ``first``) and every other column as read; ``task`` and
    ``method``, where present, are normalised (empty: ``yes-no``, ``constant``).  Rows of the ``reference`` group are
    dropped.  Answers to a shared original (group ``original``, see
    :func:`expand_shared_originals`) become the level 0 of every group that shares
    it, marked ``shared_copy`` beyond the first; never of a catch group
    (``catch_groups``, the design's ``[exclusions]``).  A first answer that was shown
    again at the end (a row of the same participant, session and trial with
    ``repeat`` = 1, see :func:`use_repeats`) is left out: the repeat stands in its
    place.  Raises :class:`ResponsesError` naming the file, the line and what
    was expected.

    Parameters
    ----------
    source : pandas.DataFrame, str or pathlib.Path
        A table, a CSV file or a study folder.
    name : str, optional
        How errors name a DataFrame source.
    catch_groups : sequence of str, optional
        The attention-check groups: they show their own stimuli only and never take
        the shared originals' answers.

    Returns
    -------
    pandas.DataFrame

    Raises
    ------
    ResponsesError
        Naming the file, line and column.
    NeedsExportError
        For a study folder without ``responses.csv``.

    Examples
    --------
    >>> from flipstudy.analysis import load_responses
    >>> from flipstudy.analysis.simulate import paper_panel
    >>> df = load_responses(paper_panel(2, seed=0))
    >>> df["incorrect"].dtype.kind, sorted(df["participant"].unique())
    ('i', ['P01', 'P02'])
    """
    df, where, line_offset = _read_table(source, name)

    def line(i) -> str:
        return f"line {i + line_offset}" if line_offset else f"row {i}"

    missing = [c for c in REQUIRED if c not in df.columns]
    if missing:
        raise ResponsesError(f"{where}: missing column(s) {', '.join(missing)}; a response table "
                             f"needs at least {', '.join(REQUIRED)} (DESIGN.md: {', '.join(DESIGN_COLUMNS)})")
    df = df.reset_index(drop=True)
    for col in ("participant", "group", "response"):
        bad = df[col].isna()
        if bad.any():
            i = int(np.flatnonzero(bad.to_numpy())[0])
            raise ResponsesError(f"{where}: {line(i)}: empty '{col}' ({int(bad.sum())} row(s) in all)")
    df["participant"] = df["participant"].astype(str)
    df["group"] = df["group"].astype(str).str.strip()
    df = df[~df["group"].str.lower().isin(IGNORED_GROUPS)].copy()
    lvl = pd.to_numeric(df["level"], errors="coerce")
    bad = lvl.isna() | ~np.isfinite(lvl)
    if bad.any():
        i = int(df.index[bad.to_numpy()][0])
        raise ResponsesError(f"{where}: {line(i)}: level {df.loc[i, 'level']!r} is not a number "
                             f"(expected the nominal error in percent, 0 = original)")
    resp = df["response"].astype(str).str.strip().str.lower()
    task = _norm_column(df, "task", TASKS, where, line, "yes-no")
    if "method" in df.columns:
        _norm_column(df, "method", METHODS, where, line, "constant")
    afc = (task == "2afc").to_numpy()
    bad = ~resp.isin(("correct", "incorrect")) & ~afc
    if bad.any():
        i = int(df.index[bad.to_numpy()][0])
        raise ResponsesError(f"{where}: {line(i)}: response {df.loc[i, 'response']!r} is neither "
                             f"'correct' nor 'incorrect' ({int(bad.sum())} such row(s))")
    detected = _detected(df, resp, afc, where, line)
    df = df.assign(level=lvl.astype(float), response=resp,
                   incorrect=((resp == "incorrect").to_numpy() & ~afc).astype(np.int8),
                   detected=detected.astype(np.int8)).reset_index(drop=True)
    if df.empty:
        raise ResponsesError(f"{where}: no trials to analyse (after dropping 'reference' rows)")
    return expand_shared_originals(use_repeats(df, where), where, catch_groups)


def _detected(df, resp, afc, where, line) -> np.ndarray:
    """Was the error detected: a yes/no answer "incorrect"; a 2AFC answer (rows ``afc``)
    that chose the original as the correct one, by column ``first``."""
    detected = (resp == "incorrect").to_numpy()
    if not afc.any():
        return detected
    bad = ~resp.isin(("first", "second")) & afc
    if bad.any():
        i = int(df.index[bad.to_numpy()][0])
        raise ResponsesError(f"{where}: {line(i)}: 2AFC response {df.loc[i, 'response']!r} is "
                             f"neither 'first' nor 'second' ({int(bad.sum())} such row(s))")
    first = (df["first"] if "first" in df.columns else pd.Series("", index=df.index))
    first = first.fillna("").astype(str).str.strip().str.lower()
    bad = ~first.isin(("original", "modified")) & afc
    if bad.any():
        i = int(df.index[bad.to_numpy()][0])
        raise ResponsesError(f"{where}: {line(i)}: a 2AFC answer needs column 'first' = "
                             f"'original' or 'modified' (what was shown first), got "
                             f"{df.loc[i, 'first'] if 'first' in df.columns else 'no such column'!r}")
    chose_original = (resp == "first") == (first == "original")
    return np.where(afc, chose_original.to_numpy(), detected)


def _read_table(source, name):
    """(table, how errors name it, the file line of row 0 or None for a DataFrame)."""
    if isinstance(source, pd.DataFrame):
        return source.copy(), name or "responses table", None
    path = resolve_responses_path(source)
    where = str(path)
    try:
        df = pd.read_csv(path, dtype={"participant": str, "group": str, "response": str,
                                      "stimulus": str, "session": str})
    except pd.errors.EmptyDataError:
        raise ResponsesError(f"{where}: the file is empty (expected a header line with "
                             f"{', '.join(DESIGN_COLUMNS)})") from None
    except pd.errors.ParserError as e:
        raise ResponsesError(f"{where}: not a readable CSV ({e})") from None
    return df, where, 2                      # header is line 1


def _norm_column(df: pd.DataFrame, col: str, allowed, where, line, default) -> pd.Series:
    """Column ``col`` lower-cased with empty cells as ``default`` (written back to
    ``df``); a value outside ``allowed`` is refused naming its line.  A table
    without the column gives ``default`` everywhere (and is left as it is)."""
    if col not in df.columns:
        return pd.Series(default, index=df.index)
    v = df[col].fillna("").astype(str).str.strip().str.lower().replace("", default)
    bad = ~v.isin(allowed)
    if bad.any():
        i = int(df.index[bad.to_numpy()][0])
        raise ResponsesError(f"{where}: {line(i)}: {col} {df.loc[i, col]!r}: expected one of "
                             f"{', '.join(allowed)}")
    df[col] = v
    return v


def use_repeats(df: pd.DataFrame, where: str = "responses table") -> pd.DataFrame:
    """The answers with each repeated trial counted once: its repeat.

    A web site exported with ``[session] repeat_dropped = true`` shows a trial whose
    video dropped too many frames once more at the end; the table keeps both answers,
    the first (``repeat`` = 0, ``playback_flagged`` = true) and the repeat
    (``repeat`` = 1, same participant, session and trial).  The first is left out
    here, so the repeat replaces it in every count and d′; a flagged answer without a
    repeat stays.  Tables without a ``repeat`` column are returned as they are.

    >>> t = pd.DataFrame({"participant": ["P1"] * 3, "session": ["1"] * 3, "trial": [1, 2, 2],
    ...                   "repeat": [0, 0, 1], "response": ["correct", "incorrect", "correct"]})
    >>> use_repeats(t)[["trial", "repeat", "response"]].values.tolist()
    [[1, 0, 'correct'], [2, 1, 'correct']]
    """
    if "repeat" not in df.columns:
        return df
    rep = pd.to_numeric(df["repeat"], errors="coerce").fillna(0)
    bad = ~rep.isin((0, 1))
    if bad.any():
        i = int(df.index[bad.to_numpy()][0])
        trial = f" trial {df.loc[i, 'trial']}" if "trial" in df.columns else ""
        raise ResponsesError(f"{where}: participant {df.loc[i, 'participant']}{trial}: repeat "
                             f"{df.loc[i, 'repeat']!r}: expected 0 (the trial's answer) or 1 (the "
                             f"trial shown once more at the end)")
    keys = [c for c in ("participant", "session", "trial") if c in df.columns]
    if "trial" not in keys or not (rep == 1).any():
        return df
    idx = pd.MultiIndex.from_frame(df[keys].astype(str))
    superseded = (rep == 0).to_numpy() & idx.isin(idx[(rep == 1).to_numpy()])
    return df[~superseded].reset_index(drop=True)


def combine_responses(sources) -> pd.DataFrame:
    """Several response tables (paths or study folders) as one table to analyse.

    Each is read and checked on its own first, so an error names its file and
    line; a ``source`` column says where each row came from (its own ``source``
    column where it has one, e.g. ``web-jatos``, else ``local``).  A participant
    ID found in two tables is refused: two tables never mix one person's answers.
    """
    frames, owner = [], {}
    for s in sources:
        path = resolve_responses_path(s)
        load_responses(path)
        df = pd.read_csv(path, dtype={"participant": str, "group": str, "response": str,
                                      "stimulus": str, "session": str})
        if "source" not in df.columns:
            df["source"] = "local"
        df["source"] = df["source"].fillna("local")
        for pid in dict.fromkeys(df["participant"].astype(str)):
            if pid in owner:
                raise ResponsesError(f"{path}: participant {pid} is also in {owner[pid]}; the tables "
                                     f"must not share participant IDs (nor be one table twice)")
            owner[pid] = path
        frames.append(df)
    return pd.concat(frames, ignore_index=True)


def expand_shared_originals(df: pd.DataFrame, where: str = "responses table",
                            catch_groups=()) -> pd.DataFrame:
    """The answers to the shared originals as level 0 of each group that shares them.

    Rows of group ``original`` (one original per base clip, shown ``repetitions``
    times, which the angular-momentum groups of the paper's design compare with)
    are copied, as level 0, into every group without a level 0 of its own — of the
    originals' ``kind`` when the table has a ``kind`` column (so a take-off group
    keeps its own original), but never into a catch group (``catch_groups``: its
    trials are gross errors only, and its rows are exactly the catch trials a
    participant saw).  Every group's d′ is then computed against those
    same answers, and each sharing group's level-0 cell shows them (the paper's
    Table 2: 72 in all four angular-momentum groups).  The copies carry
    ``shared_original = True`` and, beyond the first, ``shared_copy = True`` (count
    trials with ``~shared_copy``); the ``original``
    group itself is not a row of the tables.  Which group holds the first copy
    follows the groups' names (:func:`group_order` of them sorted), not the
    order of the rows.  A table without such rows is returned as it is
    (``shared_copy`` all False)."""
    is_orig = (df["group"] == SHARED_ORIGINAL).to_numpy()
    df = df.assign(shared_copy=False, shared_original=False)
    if not is_orig.any():
        return df
    orig = df[is_orig]
    bad = orig["level"] != 0
    if bad.any():
        raise ResponsesError(f"{where}: group '{SHARED_ORIGINAL}' holds the shared originals, level 0; "
                             f"found level {orig.loc[bad, 'level'].iloc[0]:g}")
    rest = df[~is_orig]
    has0 = set(rest.loc[rest["level"] == 0, "group"])
    # 2AFC groups compare with the original in every trial, QUEST+ groups show their own
    # level 0: neither takes the shared originals' answers
    other = np.zeros(len(rest), bool)
    if "task" in rest.columns:
        other |= (rest["task"] == "2afc").to_numpy()
    if "method" in rest.columns:
        other |= (rest["method"] == "quest+").to_numpy()
    has0 |= set(rest.loc[other, "group"])
    kinds = None
    if "kind" in df.columns:
        kinds = set(orig["kind"].dropna().astype(str))
    has0 |= set(catch_groups)
    targets = []
    for g in group_order(sorted(set(rest["group"]))):
        if g in has0:
            continue
        if kinds is not None:
            gk = set(rest.loc[rest["group"] == g, "kind"].dropna().astype(str))
            if gk and not gk & kinds:
                continue
        targets.append(g)
    if not targets:
        raise ResponsesError(f"{where}: answers to shared originals (group '{SHARED_ORIGINAL}') but "
                             f"every group has its own level 0; nothing shares them")
    copies = [orig.assign(group=g, shared_copy=i > 0, shared_original=True)
              for i, g in enumerate(targets)]
    return pd.concat([rest] + copies, ignore_index=True)


def group_order(groups) -> list[str]:
    """Default-design groups in the paper's order, then the others as they first appear."""
    seen = list(dict.fromkeys(groups))
    known = [g for g in DEFAULT_GROUP_ORDER if g in seen]
    return known + [g for g in seen if g not in known]


def level_order(levels) -> list[float]:
    """Levels by magnitude, then sign (0, 10, −10, 20, …)."""
    return sorted(set(float(x) for x in levels), key=lambda v: (abs(v), v < 0))


_TRUE = {"1", "true", "yes", "y", "t"}


def _truthy(col: pd.Series) -> pd.Series:
    if col.dtype == bool:
        return col
    return col.astype(str).str.strip().str.lower().isin(_TRUE)


def select_participants(df: pd.DataFrame, *, include_simulated: bool = False,
                        include_incomplete: bool = False) -> tuple[pd.DataFrame, dict]:
    """Leave out simulated participants and incomplete sessions (unless asked to
    keep them) and say who was used.

    A participant is simulated when the table says so: column ``simulated``
    true, or (tables exported before that column) ``input`` = ``simulated``.  A
    session is incomplete when column ``complete`` is false.  Tables without
    these columns cannot tell, and the returned ``marked`` says so.  Returns the
    selected rows and ``{"n": used participants, "real": [...], "simulated":
    [...used], "simulated_left_out": [...], "incomplete_left_out": ["P07/1 (6
    answers)", ...], "incomplete_kept": [...], "marked": {"simulated": bool,
    "complete": bool}}``.
    """
    if "simulated" in df.columns:
        sim_row = _truthy(df["simulated"])
    elif "input" in df.columns:
        sim_row = df["input"].astype(str).str.strip() == "simulated"
    else:
        sim_row = pd.Series(False, index=df.index)
    sim_ids = set(df.loc[sim_row, "participant"])
    marked = {"simulated": "simulated" in df.columns or "input" in df.columns,
              "complete": "complete" in df.columns}
    keep = pd.Series(True, index=df.index)
    left_sim = []
    if not include_simulated:
        left_sim = sorted(sim_ids)
        keep &= ~df["participant"].isin(sim_ids)
    inc_left, inc_kept = [], []
    if marked["complete"]:
        inc = ~_truthy(df["complete"])
        session = df["session"].astype(str) if "session" in df.columns else pd.Series("1", index=df.index)
        for (p, s), n in df[inc & keep].groupby([df["participant"], session]).size().items():
            (inc_kept if include_incomplete else inc_left).append(f"{p}/{s} ({n} answers)")
        if not include_incomplete:
            keep &= ~inc
    out = df[keep].reset_index(drop=True)
    used = sorted(set(out["participant"]))
    info = {"n": len(used), "real": [p for p in used if p not in sim_ids],
            "simulated": [p for p in used if p in sim_ids], "simulated_left_out": left_sim,
            "incomplete_left_out": inc_left, "incomplete_kept": inc_kept, "marked": marked}
    return out, info


def participants_label(info: dict) -> str:
    """One line for every table and figure: which participants it used, e.g.
    ``"N = 12 participants (12 real, 0 simulated); left out: 19 simulated, 2
    incomplete sessions"``."""
    s = (f"N = {info['n']} participant{'s' if info['n'] != 1 else ''} "
         f"({len(info['real'])} real, {len(info['simulated'])} simulated)")
    left = []
    if info["simulated_left_out"]:
        left.append(f"{len(info['simulated_left_out'])} simulated")
    if info["incomplete_left_out"]:
        n = len(info["incomplete_left_out"])
        left.append(f"{n} incomplete session{'s' if n != 1 else ''}")
    if left:
        s += "; left out: " + ", ".join(left)
    if info["incomplete_kept"]:
        s += f"; {len(info['incomplete_kept'])} incomplete session(s) kept"
    if not info["marked"]["simulated"]:
        s += "; the table does not mark simulated participants"
    return s
