"""Identification over any declared model (``acid.models``), the only fitter: ``fit.py``
(least squares where an equation allows it, CVXPY bounds, Huber loss, output error with
latent initial states, HAC, identified combinations, multi-start, per-experiment parameters;
the parameter file), ``linear.py``, ``oe.py``, ``validate.py`` (multi-start open-loop
prediction), ``analysis.py`` (predict, compare, resid), ``data.py`` (a dataset read for a
declaration)."""
