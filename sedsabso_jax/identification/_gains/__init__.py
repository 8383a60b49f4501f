"""Drive gains (torque per unit of the recorded current) identified together with the
robot's torque model from recordings without and with a payload of known mass."""
