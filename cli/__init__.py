"""The ``flightid`` command line: the top layer, and the only one that imports typer and
rich (import-linter checks it).

``app`` declares the commands and registers the command functions of one module per
command group: ``trim_truth`` (``trim``, ``truth``), ``simulate``, ``bridge`` (``bridge
serve|record|fly``, ``convert``), ``frequency_response``, ``compatibility``. Each
command is a thin call of a library function plus printing; ``progress`` draws the rich
progress bar that the library reports to through a plain callback.
"""
