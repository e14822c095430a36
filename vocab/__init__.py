"""flipstudy.vocab: the study's vocabulary, on its own floor below the physics.

The words every part speaks: the error kinds (:mod:`~flipstudy.vocab.kinds`), the
design, the stimulus set contract, the answer record, the calibration format and
the one psychometric function.  It imports no physics (no module of
:mod:`flipstudy.stimuli`, render, study or analysis): ``stimuli``, ``render``,
``study`` and ``analysis`` import it.
"""
