"""How the linear values of a torque model are fitted to its rows: the estimator
interface, least squares and its physically consistent form, fits of the rows
themselves (L1, Levenberg-Marquardt, a box search) and the normal equations."""
