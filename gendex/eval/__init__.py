"""Evaluating policies on GenDex tasks: the episode runner (:mod:`gendex.eval.runner`)."""
