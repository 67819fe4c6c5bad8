"""Input-design comparisons over Monte Carlo studies: ``experiment`` (the designs, their
equalisation and cards), ``comparison`` (the comparison flown with the same seeds),
``report`` (its figures, HTML page and Markdown table), ``optimize`` (``design-optimize``:
a multisine optimised for the predicted bounds, against the built-in designs)."""
