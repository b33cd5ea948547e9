"""Planning: the world a plan acts in, the OE condensing variants (oe/), the switch planners (ss/), their
assembly into a timed plan, and solve()."""
