"""Records in the exported site's names: the tests that fabricate a site's records write
them in the study's names (stimulus, group, level) for readability; :func:`as_site_writes`
turns them into what the site's browser writes (opaque video and group names from the
study's ``web/site-map.json``, created as ``export-web`` creates it; no clip, kind or
level), so ``import-web`` reads them through the map as it reads a real site's."""
from flipstudy.study.session import load_study

HIDDEN = ("level", "clip", "kind")


def site_map(study):
    from flipstudy.study.web.opaque import site_map as make     # (imported late: the tests of the
    return make(study)                                           # names collect without them)


def as_site_writes(study_dir, recs):
    """``recs`` (dicts in the study's names) as the site writes them."""
    st = load_study(study_dir)
    m = site_map(st)
    between = bool(st.design.online.between)
    out = []
    for r in recs:
        r = dict(r)
        if between and r.get("condition"):
            r["condition"] = m.group(r["condition"])
        if r.get("record") == "start":
            r["order"] = " ".join(m.video(s) for s in r["order"].split(" ")) if r.get("order") else r.get("order")
            if r.get("block_order"):
                r["block_order"] = " ".join(m.group(g) for g in r["block_order"].split(" "))
        elif r.get("record") == "answer":
            r["stimulus"], r["group"] = m.video(r["stimulus"]), m.group(r["group"])
            if r.get("original"):
                r["original"] = m.video(r["original"])
            for k in HIDDEN:
                r.pop(k, None)
        out.append(r)
    return out


def site_name(study_dir, stimulus):
    """The opaque name the site gives ``stimulus`` (its video's file name without ``.mp4``)."""
    return site_map(load_study(study_dir)).video(stimulus)


def study_names(study_dir, space="stimulus"):
    """The study's map of opaque names in ``space`` ("stimulus" or "group"): opaque → name."""
    return site_map(load_study(study_dir)).names[space]


def condition_words(study_dir):
    """Every name of a condition a participant must not read: stimuli (the examples' too),
    groups (the design's and the shared originals'), error kinds and profiles.  Not the
    examples' group (and kind), "reference": the page says of each example that it is a
    correct motion (and its instructions say "reference point")."""
    from flipstudy.stimuli.contract import REFERENCE_GROUP
    st = load_study(study_dir)
    words = {g.name for g in st.design.groups}
    for r in st.manifest:
        words |= {r.stimulus} if r.group == REFERENCE_GROUP else {r.stimulus, r.group, r.kind, r.profile}
    return sorted(w for w in words if w)


def nothing_imported(study_dir):
    """Nothing in ``STUDY/web`` but the site map (written by whoever made the records, as
    export-web does): no table, no kept file, no ledger."""
    from pathlib import Path
    web = Path(study_dir) / "web"
    return not web.exists() or sorted(p.name for p in web.iterdir()) == ["site-map.json"]
