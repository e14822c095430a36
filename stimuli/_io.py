"""Small file helpers shared by every layer (the lowest one that needs them)."""
from __future__ import annotations

import os
import tempfile
from pathlib import Path


def atomic_write_text(path, text: str) -> None:
    """Write ``text`` (UTF-8, newlines as given) to ``path`` through a temporary file
    in the same folder and ``os.replace``, so a reader never sees a half-written file."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w", newline="", encoding="utf-8") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def missing_file_hint(path, spec, *, base=None, also=()) -> str:
    """What to say after "no such file" for ``path`` (the file looked for; ``spec``:
    the name as the user wrote it): where a relative ``spec`` was resolved
    (``base``: the folder it was resolved against; default the working folder) and
    the closest names in the folder looked in, or in ``also`` (built-in names).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     _ = (pathlib.Path(tmp) / "backflip.bvh").write_text("")
    ...     hint = missing_file_hint(pathlib.Path(tmp) / "bakflip.bvh", "bakflip.bvh", base=tmp)
    ...     print("did you mean 'backflip.bvh'?" in hint, "resolved against" in hint)
    True True
    """
    import difflib
    path, parts = Path(path), []
    if not Path(spec).is_absolute():
        where = Path(base) if base is not None else Path.cwd()
        parts.append(f"a relative path, resolved against {where.resolve()}")
    folder, names = path.parent, []
    if folder.is_dir():
        try:
            names = sorted(p.name for p in folder.iterdir() if not p.name.startswith("."))[:5000]
        except OSError:
            pass
    else:
        parts.append(f"the folder {folder} does not exist")
    sub = Path(spec).parent
    close = [c if sub == Path(".") else str(sub / c)
             for c in difflib.get_close_matches(path.name, names, n=3, cutoff=0.6)]
    close += difflib.get_close_matches(str(spec), list(also), n=2, cutoff=0.6)
    if close:
        parts.append("did you mean " + " or ".join(repr(c) for c in close) + "?")
    return "; ".join(parts)
