"""How the few parameters a torque model's columns read nonlinearly are searched: the
methods (one object each) and what they read of a problem."""
