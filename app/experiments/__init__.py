"""The paper's simulation study on our model (``pelvic-walk experiments``).

- ``definitions``: what runs, as data (:class:`RunSpec`, :class:`Study`), and the paper's
  numbers to put beside ours (Table 1 copied with its citation).
- ``runner``: runs every needed run once over a process pool, keeps only what each section
  needs, writes ``results.json``, ``figures/*.png`` and ``report.md``.
- ``sections``: turns the run results into each section's numbers and verdicts.
- ``figures``: matplotlib (Agg) figures.
- ``report``: the markdown report.
"""
