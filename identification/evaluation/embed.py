"""PNG images embedded in an HTML report as base64 data, so the file opens anywhere alone."""

from __future__ import annotations

import base64
import html
import io
from pathlib import Path

from matplotlib.figure import Figure


def png_img(image: Figure | bytes | str | Path, alt: str, dpi: int = 110) -> str:
    """An ``<img>`` element holding a PNG image as base64 data.

    Parameters
    ----------
    image : Figure, bytes, str or Path
        A matplotlib figure (saved at ``dpi``, cropped to its content), PNG bytes, or a PNG
        file.
    alt : str
        The alternative text (HTML-escaped here).
    dpi : int
        Dots per inch of a figure.

    Returns
    -------
    str
        ``<img alt='...' src='data:image/png;base64,...'>``.
    """
    if isinstance(image, Figure):
        buf = io.BytesIO()
        image.savefig(buf, format="png", dpi=dpi, bbox_inches="tight")
        data = buf.getvalue()
    elif isinstance(image, bytes):
        data = image
    else:
        data = Path(image).read_bytes()
    return (f"<img alt='{html.escape(alt)}' "
            f"src='data:image/png;base64,{base64.b64encode(data).decode()}'>")
