"""The leading candidates judged with the turbulence modelled as process noise
(``leading``: filter error on the fitted and held-out windows)."""
