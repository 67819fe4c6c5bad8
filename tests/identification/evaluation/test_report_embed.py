"""The one way reports embed a PNG: a figure, PNG bytes or a PNG file become an <img> with
base64 data that decodes to the same PNG."""

from __future__ import annotations

import base64
import re

from matplotlib.figure import Figure

from flightid.identification.evaluation.embed import png_img

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _data(tag: str) -> bytes:
    return base64.b64decode(re.search(r"base64,([A-Za-z0-9+/=]+)'", tag).group(1))


def test_a_figure_bytes_and_a_file_give_the_same_image(tmp_path):
    fig = Figure(figsize=(2, 1))
    fig.add_subplot().plot([0, 1], [1, 0])
    tag = png_img(fig, "a <line>")
    png = _data(tag)
    assert png.startswith(PNG_SIGNATURE)
    assert tag.startswith("<img alt='a &lt;line&gt;' src='data:image/png;base64,")
    (tmp_path / "line.png").write_bytes(png)
    assert _data(png_img(png, "x")) == png == _data(png_img(tmp_path / "line.png", "x"))
