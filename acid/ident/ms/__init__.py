"""Solvers of the identification fits that scale with the data: output error as one sparse
multiple-shooting NLP (:mod:`.shooting`, ``acid fit --oe-solver ms``) and the bounded
Newton steps (Fisher information or exact Hessian) that end the prediction-error fit
(:mod:`.newton`)."""
