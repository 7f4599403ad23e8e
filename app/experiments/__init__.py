"""The paper's simulation study on our model (``pelvic-walk experiments``).

Where each thing is:

- ``paper``: the paper's numbers, typed once (Table 1, the limits, the kinematics, ...).
- ``definitions``: what runs, as data (:class:`Study`, the sensitivity grid and the pushes);
  a run is an ``pelvic_walk.core.run_spec.RunSpec``.
- ``worker``: one run in a worker process -> a small typed result (``runs``).
- ``runner``: every run on the run engine (``pelvic_walk.core.engine``: local process pool or Ray),
  then ``analysis``, the figures, ``results.json`` and ``report.md``.
- ``runs``: a run's typed result and how a section reads it; ``results``: the study's
  (:class:`StudyResults`, ``results.json``).
- one module per topic, its dataclasses and numbers: ``limits`` (sections 1-2), ``waist`` (3),
  ``yaw`` (4), ``energy`` (5), ``kappa`` (6), ``balance`` (7), ``robustness`` (8),
  ``sensitivity`` (9); ``analysis`` calls them all.
- ``claims``: every claim of the paper in one table: paper value, our measurement
  (``measures``), verdict rule (``verdicts``: the rules and the one verdict helper).
- ``figures``: every figure (``fig_<topic>`` modules, the style in ``fig_style``).
- ``report`` + ``templates/``: the markdown report, one jinja2 template per section;
  ``summary``: its summary at the top.
"""
