"""Steps of ``imunav lab`` (see :mod:`imunav.lab.runner`): one module per step with
``TITLE`` and ``run(ctx) -> StepResult``."""
