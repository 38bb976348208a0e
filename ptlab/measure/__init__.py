"""Measuring the renderer: its speed, its error against a reference, and the two together.

* ``metrics``: relMSE and RMSE of an image against a reference;
* ``bench``: ``ptlab bench``, samples and rays per second and the share spent in ray queries;
* ``against``: ``ptlab bench --against``, ptlab's time against the homework's compiled C++
  path tracer, whole process against whole process;
* ``converge``: ``ptlab converge``, error against time for several estimators;
* ``charts``: the convergence chart and the equal-time strip that ``converge`` draws;
* ``mitsuba_export``, ``mitsuba_render``, ``against_mitsuba``: a ptlab scene written for
  Mitsuba 3, rendered by it (an optional dependency), and the two renderers compared
  (``scripts/against_mitsuba.py``).
"""
