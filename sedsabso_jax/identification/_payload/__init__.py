"""A body fixed to a link: the payload as a term, its identification, the result."""
