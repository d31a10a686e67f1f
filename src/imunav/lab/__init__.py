"""Orchestration: ``imunav lab`` (a sequence of steps writing one report folder), batches of recordings, seeded
Monte Carlo runs, run folders and the HTML / Markdown reports.  Everything below this package (the estimators, the
simulators, the readers) knows nothing of it.

=================  ================================================================================
module             owns
=================  ================================================================================
``runner``         ``run_lab``: runs the steps, checks the specification, writes the report folder;
                   re-exports the names of ``config`` and of the step API
``config``         the lab's TOML definition (``LabConfig``), ``STEPS``, ``SIMULATION_ONLY``
``steps``          one module per step, and the step API (``steps._api``: ``LabContext``, ``StepResult``)
``batch``          a folder of recordings calibrated, characterised or simulated in parallel
``montecarlo``     seeded Monte Carlo and batch runs, local processes or a Dask cluster
``runfolder``      run folders: manifest, atomic files, refusal to overwrite another run
``report``         HTML reports, the lab's Markdown / HTML (``report.lab``), the batch report, the catalogue
=================  ================================================================================

The package itself imports nothing (``imunav attitude montecarlo`` imports :mod:`imunav.lab.montecarlo` without
the lab runner).  Quick use::

    from imunav.lab.runner import run_lab
    result = run_lab("lab-report", rng=0)
"""
