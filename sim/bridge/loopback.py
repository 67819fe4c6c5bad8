"""A record streamed through the bridge to a recorder on this machine: the air side and
the ground side joined by a pty pair or loopback UDP.
"""

from __future__ import annotations

import threading
from pathlib import Path

from flightid.record import FlightRecord
from flightid.sim.bridge.air.serve import BridgeConfig, serve_record
from flightid.sim.bridge.ground.recording import record_stream
from flightid.sim.bridge.link import Link, SerialLink, UdpLink, open_pty_pair


def record_bridged(
    record: FlightRecord, tlog_path: str | Path, config=None, *, transport: str = "pty",
    port: int = 0,
):
    """Stream a record through the bridge to a recorder on this machine.

    Over a pty pair (``transport='pty'``) or loopback UDP (``'udp'``); the tlog is written.

    Parameters
    ----------
    record : FlightRecord
        The flight to stream, SI channels.
    tlog_path : str or pathlib.Path
        The .tlog file the recorder writes.
    config : BridgeConfig, optional
        Bridge settings; default ``BridgeConfig()``.
    transport : str, optional
        "pty" (default) or "udp".
    port : int, optional
        UDP port for ``'udp'``; 0 (default) = any free port.

    Returns
    -------
    tuple
        (air-side BridgeReport, ground-side RecordingReport).

    Raises
    ------
    ValueError
        For an unknown transport.
    TimeoutError
        When the recorder does not finish within 60 s of the end of the stream.
    """
    config = config or BridgeConfig()
    stop = threading.Event()
    result: dict = {}
    if transport == "pty":
        pty = open_pty_pair()
        ground: Link = SerialLink(pty.slave_path, config.baud or 115200)
        air: Link = pty.master_link()
        closers = [ground.close, pty.close]
    elif transport == "udp":
        ground = UdpLink(("127.0.0.1", port), listen=True)
        air = UdpLink(ground.local_address, listen=False)
        closers = [ground.close, air.close]
    else:
        raise ValueError(f"unknown transport {transport!r}; use 'pty' or 'udp'")

    def run_ground() -> None:
        try:
            result["ground"] = record_stream(ground, tlog_path, idle_timeout=30.0, stop=stop)
        except BaseException as exc:  # surfaced below
            result["error"] = exc

    thread = threading.Thread(target=run_ground, daemon=True)
    thread.start()
    try:
        air_report = serve_record(record, air, config)
    finally:
        stop.set()
        thread.join(60.0)
        for close in closers:
            close()
    if "error" in result:
        raise result["error"]
    if "ground" not in result:
        raise TimeoutError("the recorder did not finish within 60 s of the end of the stream")
    return air_report, result["ground"]
