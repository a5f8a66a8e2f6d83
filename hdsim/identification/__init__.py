"""Model against measurement: the fit, residual views, the diagnosis and its report."""
