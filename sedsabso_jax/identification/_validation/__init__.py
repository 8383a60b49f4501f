"""How well a fit predicts what it was not fitted to: the splits, their validation, the
choice of a model by it, the error metrics and how far new data extrapolate."""
