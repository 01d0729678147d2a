"""Control over any declared model: the optimal-control builder (``ocp``) and its layout."""
