"""The paper's simulation study on our model (``pelvic-walk experiments``).

Where each thing is:

- ``paper``: the paper's numbers, typed once (Table 1, the limits, the kinematics, ...).
- ``definitions``: what runs, as data (:class:`RunSpec` with any parameter override,
  :class:`Study`), and which extracts each section needs.
- ``worker``: one run in a worker process -> a small typed :class:`RunResult`.
- ``runner``: runs every needed run once over a process pool, analyses, writes
  ``results.json``, ``figures/*.png`` and ``report.md``.
- ``results``: the typed results (a run's, each section's, the whole study's).
- ``sections``: each section's numbers from the run results.
- ``claims``: every claim of the paper in one table: paper value, our measurement
  (``measures``), verdict rule (``verdicts``: the rules and the one verdict helper).
- ``figures``: matplotlib (Agg) figures.
- ``report`` + ``templates/``: the markdown report, one jinja2 template per section.
"""
