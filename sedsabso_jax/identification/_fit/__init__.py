"""How a torque model is fitted: the samples, the stages its terms ask for, the compiled
search of its nonlinear parameters, identify, and the uncertainty of what is found."""
