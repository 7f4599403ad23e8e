"""How fast and how many: ``pelvic-walk bench`` (:mod:`app.bench.timings`: the tick, the closed
loop, a paced live robot, the placo peer in :mod:`app.bench.peer`) and ``pelvic-walk
loadtest`` (:mod:`app.bench.loadtest`: scene viewers against a served tool, on loopback), with
:mod:`app.bench.local_server` starting a server on free loopback ports for them and the tests.
Figures are measured here, never asserted in tests.
"""
