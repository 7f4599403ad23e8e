"""The headless core: what runs the paper's layers (``controller/``) in MuJoCo, for every face.

The command line (``app/cli``), the page and its live sessions (``app/web``, ``app/live``),
the study (``app/experiments``), the bench (``app/bench``) and the notebooks (``pelvic_walk``'s
public names) all run walks through these modules, and nothing here imports a face: no
fastapi, uvicorn, viser or mjviser, no ``app`` module (``pyproject.toml``'s import contracts,
``tests/test_core.py``).

In the order the data flows:

- ``params``: parameters by name, from text (the field specs of ``controller/params.py``);
- ``world``: one robot in MuJoCo; ``session``: world + walker + what each period measured;
  ``metrics``: the time series' columns; ``summary``: a run's summary keys;
- ``run_spec``: one run as plain data (:class:`RunSpec`); ``run``: **the one run path**,
  :func:`~pelvic_walk.core.run.run`, with its hooks (pushes, a frame sink, a stop);
- ``frames``: the plain-data frames a live session publishes; ``capture``: a headless run's
  frames and plot rows (the sink of ``simulate --record`` and the notebooks' player);
- ``pushes``: the push study (a shove at mid-step, the largest survived);
- ``engine``: many runs on one engine (a local process pool, Ray, or in-process);
  ``grid``, ``measure``, ``sweep_output``: a sweep's grid, what a cell measures, its files;
- ``methods``: how strategies are named and drawn; ``report_dir``: where the study's reports are.
"""
