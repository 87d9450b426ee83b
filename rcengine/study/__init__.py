"""The thesis's rolling learn/predict study: ``run`` (tasks and workers), ``analysis`` (tables,
summary, Sun versus Basic, free-floating validation), ``report`` (files), ``figures`` (the
thesis's figures)."""
