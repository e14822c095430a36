"""Moved to :mod:`flipstudy.vocab.calibration`, the study's vocabulary below the physics;
this name stays, for the callers that import it from here (the same module object)."""
import sys

from flipstudy.vocab import calibration as _moved

sys.modules[__name__] = _moved
