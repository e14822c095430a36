"""Moved to :mod:`flipstudy.vocab.contract`, the study's vocabulary below the physics.

This name stays for the callers that import from it: every name of that module is
bound here too (the same objects)."""
from flipstudy.vocab import contract as _moved

globals().update({k: v for k, v in vars(_moved).items() if not k.startswith("__") or k == "__all__"})
