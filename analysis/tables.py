"""The paper's table layout: "72 (.00)" — rating, then d′ in parentheses.

Groups are rows, levels are columns; groups that share the same set of levels
form one block with its own header row (the paper's Table 2 has two blocks:
angular momentum 0/17/25/37/50 % and take-off angle 0/10/20/30/40 %).
Levels are headed in their unit: percent, or poses per second for a ``pose-rate``
group (``kinds``: group → error kind, :func:`.units.group_kinds`), which forms
its own block and its own columns.
"""
from __future__ import annotations

import math
import re
import unicodedata

import pandas as pd

from .io import group_order, level_order
from .units import level_unit

MISSING = "—"


def fmt_dprime(d: float, minus: str = "-") -> str:
    """Two decimals, no leading zero, sign kept: 0.05 → ".05", −0.22 → "-.22", 1.4 → "1.40".

    Parameters
    ----------
    d : float
    minus : str

    Returns
    -------
    str

    Examples
    --------
    >>> from flipstudy.analysis import fmt_dprime
    >>> fmt_dprime(0.05), fmt_dprime(-0.22), fmt_dprime(1.4)
    ('.05', '-.22', '1.40')
    """
    if d is None or not math.isfinite(d):
        return MISSING
    r = round(float(d), 2)
    if r == 0:
        return ".00"
    s = f"{abs(r):.2f}"
    if s.startswith("0"):
        s = s[1:]
    return (minus if r < 0 else "") + s


def fmt_cell(rating: float, d: float, minus: str = "-") -> str:
    """``"72 (.00)"``: the rating rounded to a whole percent, then d′.

    Parameters
    ----------
    rating : float
        Percent of answers "correct".
    d : float
        d′.
    minus : str
        The minus sign to write.

    Returns
    -------
    str

    Examples
    --------
    >>> from flipstudy.analysis import fmt_cell
    >>> fmt_cell(71.6, -0.22, "−")
    '72 (−.22)'
    """
    if rating is None or not math.isfinite(rating):
        return MISSING
    return f"{int(math.floor(rating + 0.5))} ({fmt_dprime(d, minus)})"


def _cell(sub: pd.DataFrame, lv: float, minus: str) -> str:
    """A cell of a group's rows (indexed by level): yes/no rating or, for a 2AFC row
    (``task`` = ``2afc``), percent correct choices, then d′."""
    r = sub.loc[lv]
    if "task" in sub.columns and r["task"] == "2afc":
        return fmt_cell(100.0 * r["p_correct"], r["dprime"], minus)
    return fmt_cell(r["rating_pct"], r["dprime"], minus)


def fmt_level(lv: float, unit: str = "%") -> str:
    """A level as a column head: ``"17 %"``, ``"−25 %"``, ``"15 poses/s"``."""
    return f"{lv:g} {unit}".replace("-", "−")


def blocks(table: pd.DataFrame, kinds: dict | None = None) -> list[tuple[list[float], list[str]]]:
    """Groups sharing a level set and unit, in table order: [(levels, groups), …]."""
    kinds = kinds or {}
    out: dict[tuple, list[str]] = {}
    for g in group_order(table["group"].unique()):
        lv = tuple(level_order(table.loc[table["group"] == g, "level"]))
        out.setdefault((lv, level_unit(kinds.get(g))), []).append(g)
    return [(list(k[0]), v) for k, v in out.items()]


def paper_layout(table: pd.DataFrame, minus: str = "-", kinds: dict | None = None) -> pd.DataFrame:
    """Wide table, one row per group, one column per level (union of all
    levels, sorted by magnitude; percent levels first, then those of pose-rate
    groups in poses/s); cells ``"72 (.00)"``, empty where a group did not test a
    level.

    Parameters
    ----------
    table : pandas.DataFrame
        The long table of :func:`summarize` (columns group, level, rating_pct, dprime).
    minus : str
        The minus sign to write.
    kinds : dict, optional
        Group → error kind (pose-rate levels are poses/s).

    Returns
    -------
    pandas.DataFrame

    Examples
    --------
    >>> from flipstudy.analysis import load_responses, paper_layout, summarize
    >>> from flipstudy.analysis.simulate import paper_panel
    >>> table, _, _ = summarize(load_responses(paper_panel(19, seed=0)), n_boot=100)
    >>> paper_layout(table).set_index("group").loc["abrupt-decrease", "0 %"]
    '66 (.00)'
    """
    kinds = kinds or {}
    groups = group_order(table["group"].unique())
    unit = {g: level_unit(kinds.get(g)) for g in groups}
    cols = []
    for u in dict.fromkeys(sorted(unit.values(), key=lambda u: u != "%")):
        mine = table["group"].map(lambda g: unit.get(g) == u).astype(bool)
        cols += [(lv, u) for lv in level_order(table.loc[mine, "level"])]
    rows = []
    for g in groups:
        sub = table[table["group"] == g].set_index("level")
        row = {"group": g}
        for lv, u in cols:
            row[fmt_level(lv, u)] = _cell(sub, lv, minus) if lv in sub.index and u == unit[g] else ""
        rows.append(row)
    return pd.DataFrame(rows)


def _block_rows(table, levels, groups, minus):
    out = []
    for g in groups:
        sub = table[table["group"] == g].set_index("level")
        out.append([g] + [_cell(sub, lv, minus) if lv in sub.index else MISSING for lv in levels])
    return out


def to_markdown(table: pd.DataFrame, caption: str = "", kinds: dict | None = None) -> str:
    """GitHub Markdown, one table per block of groups sharing their levels.

    Parameters
    ----------
    table : pandas.DataFrame
        The long table of :func:`summarize` (columns group, level, rating_pct, dprime).
    caption : str
    kinds : dict, optional

    Returns
    -------
    str

    Examples
    --------
    >>> from flipstudy.analysis import load_responses, summarize, to_markdown
    >>> from flipstudy.analysis.simulate import paper_panel
    >>> table, _, _ = summarize(load_responses(paper_panel(19, seed=0)), n_boot=100)
    >>> print(to_markdown(table).splitlines()[0])
    | group | 0 % | 17 % | 25 % | 37 % | 50 % |
    """
    parts = []
    kinds = kinds or {}
    if caption:
        parts.append(caption + "\n")
    for levels, groups in blocks(table, kinds):
        head = ["group"] + [fmt_level(lv, level_unit(kinds.get(groups[0]))) for lv in levels]
        lines = ["| " + " | ".join(head) + " |",
                 "|" + "|".join([":---"] + ["---:"] * len(levels)) + "|"]
        for r in _block_rows(table, levels, groups, "−"):
            lines.append("| " + " | ".join(r) + " |")
        parts.append("\n".join(lines) + "\n")
    return "\n".join(parts)


#: Non-ASCII characters of our captions and labels, as LaTeX that pdflatex reads
#: without any package (the table is pure ASCII).
_TEX_UNICODE = {"d\u2032": "$d'$", "\u2032": "$'$", "\u2212": "$-$", "\u2013": "--", "\u2014": "---",
                "\u00d7": r"$\times$", "\u00b0": r"$^\circ$", "\u00b7": r"$\cdot$",
                "\u03b3": r"$\gamma$", "\u03bb": r"$\lambda$", "\u2264": r"$\leq$",
                "\u2265": r"$\geq$", "\u00b1": r"$\pm$", "\u2192": r"$\rightarrow$",
                "\u201c": "``", "\u201d": "''", "\u2018": "`", "\u2019": "'", "\u00a0": "~",
                "\u2026": r"\ldots{}"}


def _tex_escape(s: str) -> str:
    """Text as pure-ASCII LaTeX: specials escaped, the known non-ASCII characters as macros,
    accented letters without their accents (NFKD), anything else as '?'."""
    s = re.sub(r'"([^"]*)"', "\x01\\1\x02", s)          # "quoted" -> ``quoted''
    for a, b in (("\\", "\x00"), ("&", r"\&"), ("%", r"\%"), ("$", r"\$"),
                 ("#", r"\#"), ("_", r"\_"), ("{", r"\{"), ("}", r"\}"), ("~", r"\textasciitilde{}"),
                 ("^", r"\textasciicircum{}"), ("<", r"\textless{}"), (">", r"\textgreater{}"),
                 ("|", r"\textbar{}"), ('"', "''")):
        s = s.replace(a, b)
    s = s.replace("\x00", r"\textbackslash{}").replace("\x01", "``").replace("\x02", "''")
    for a, b in _TEX_UNICODE.items():
        s = s.replace(a, b)
    if not s.isascii():
        s = unicodedata.normalize("NFKD", s)
        s = "".join(c if c.isascii() else ("" if unicodedata.combining(c) else "?") for c in s)
    return "".join(c if c.isprintable() else " " for c in s)


def to_latex(table: pd.DataFrame, caption: str = "", label: str = "tab:ratings",
             kinds: dict | None = None) -> str:
    """A LaTeX table, one header row per block of groups sharing their levels, as in the
    paper.  Pure ASCII; it compiles with pdflatex and no package, and uses booktabs' rules
    when the document loads ``\\usepackage{booktabs}`` (plain ``\\hline`` otherwise).

    Parameters
    ----------
    table : pandas.DataFrame
        The long table of :func:`summarize` (columns group, level, rating_pct, dprime).
    caption : str
    label : str
    kinds : dict, optional

    Returns
    -------
    str

    Examples
    --------
    >>> from flipstudy.analysis import load_responses, summarize, to_latex
    >>> from flipstudy.analysis.simulate import paper_panel
    >>> table, _, _ = summarize(load_responses(paper_panel(19, seed=0)), n_boot=100)
    >>> tex = to_latex(table)
    >>> tex.isascii(), "tabular" in tex
    (True, True)
    """
    kinds = kinds or {}
    bl = blocks(table, kinds)
    ncol = max(len(levels) for levels, _ in bl)
    lines = [r"\begin{table}[t]", r"  \centering",
             r"  % booktabs rules when the document loads booktabs, \hline and \cline otherwise",
             r"  \providecommand{\toprule}{\hline}\providecommand{\midrule}{\hline}"
             r"\providecommand{\bottomrule}{\hline}",
             r"  \ifdefined\cmidrule\def\flipstudyrule#1{\cmidrule(lr){#1}}"
             r"\else\def\flipstudyrule#1{\cline{#1}}\fi"]
    if caption:
        lines.append(f"  \\caption{{{_tex_escape(caption)}}}")
        lines.append(f"  \\label{{{label}}}")
    lines.append(f"  \\begin{{tabular}}{{l{'r' * ncol}}}")
    lines.append(r"    \toprule")
    for bi, (levels, groups) in enumerate(bl):
        if bi:
            lines.append(r"    \midrule")
        u = level_unit(kinds.get(groups[0]))
        head = ["Error group"] + [_tex_escape(f"{lv:g} {u}").replace("-", "$-$") for lv in levels]
        head += [""] * (ncol - len(levels))
        lines.append("    " + " & ".join(head) + r" \\")
        lines.append(f"    \\flipstudyrule{{2-{len(levels) + 1}}}")
        for r in _block_rows(table, levels, groups, "$-$"):
            r = [_tex_escape(r[0])] + [c.replace(MISSING, "--") for c in r[1:]]
            r += [""] * (ncol + 1 - len(r))
            lines.append("    " + " & ".join(r) + r" \\")
    lines += [r"    \bottomrule", r"  \end{tabular}", r"\end{table}", ""]
    return "\n".join(lines)
