"""Identification over any declared model (``acid.models``): ``fit.py`` (least squares where
an equation allows it, CVXPY bounds, output error with latent initial states, HAC, multi-start,
per-experiment parameters), ``validate.py`` (multi-start open-loop prediction), ``data.py``
(a dataset read for a declaration), ``params.py`` (the fitted parameter file)."""
