"""The torque model an identification fits: its terms, each in its own module, the
model that puts them beside the base regressor, and the default's candidates."""
