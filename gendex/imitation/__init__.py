"""Learning from GenDex datasets: behaviour cloning with action chunks (:mod:`gendex.imitation.bc`)."""
