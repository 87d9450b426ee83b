"""The thesis's rolling learn/predict study: ``run`` (tasks and workers), ``report`` (tables
and files), ``figures`` (the thesis's figures)."""
