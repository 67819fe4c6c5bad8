"""Model structures: the --model table, linear perturbation models, rigid-body equations, a priori
values.
"""
