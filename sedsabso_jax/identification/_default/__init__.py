"""What the command does by default: the candidates and the rules between the options,
one call that chooses, fits and judges, and its report."""
