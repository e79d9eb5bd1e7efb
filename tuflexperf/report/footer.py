"""Every page's footer: the case, "page k of n", the inputs' short hash, the tool and date.

The pages are drawn separately (in parallel helpers, before their number is known), so the
footer is stamped when the PDF is put together (PDFium text objects in the standard
Helvetica): each page keeps a strip of :data:`FOOTER_IN` at its foot for it
(:func:`reserve`), and the PNGs are rendered from the stamped pages.
"""

from __future__ import annotations

import ctypes
from typing import Any

FOOTER_IN = 0.34  # the strip kept free at each page's foot
BASELINE_PT = 11.0  # above a printer's unprintable edge
SIDE_PT = 43.0  # 0.6 in, the text pages' margin
FONT_PT = 7.0
GREY = (90, 90, 90)
LONGEST_CASE_TEXT = 100  # characters of the case's name (and --set) before "..."


def reserve(fig: Any) -> None:
    """Keep :data:`FOOTER_IN` free at the foot of a page drawn with a layout engine (the
    constrained layout lays the page out above it); a page without one keeps it itself."""
    engine = fig.get_layout_engine()
    if engine is None or not hasattr(engine, "set"):
        return
    bottom = FOOTER_IN / fig.get_figheight()
    try:
        engine.set(rect=(0.0, bottom, 1.0, 1.0 - bottom))
    except TypeError:  # a layout engine without a rectangle (tight layout)
        return


def footer_texts(case: Any, page: int, pages: int, digest: str, version: str,
                 now: str, compared: list[str] | None = None) -> tuple[str, str]:
    """(left, right) of one page's footer: the case (and each ``--compare`` case), then page,
    inputs, tool and date."""
    left = case.name
    overrides = getattr(case, "overrides", ())
    if overrides:  # a page of a changed case is not a page of the files alone
        left += " with --set " + ", ".join(f"{k}={v:g}" for k, v in overrides)
    if compared:
        left = "A: " + left + "".join(f" vs {chr(ord('B') + k)}: {name}"
                                     for k, name in enumerate(compared))
    if len(left) > LONGEST_CASE_TEXT:
        left = left[: LONGEST_CASE_TEXT - 3] + "..."
    right = f"page {page} of {pages}  |  inputs {digest}  |  tuflexperf {version}  |  {now}"
    return left, right


def stamp(document: Any, texts: list[tuple[str, str]]) -> None:
    """Stamp ``texts[k]`` (left, right) at the foot of page ``k`` of a pypdfium2 document."""
    import pypdfium2.raw as raw

    font = raw.FPDFText_LoadStandardFont(document.raw, b"Helvetica")
    for index, (left, right) in enumerate(texts):
        page = document[index]
        try:
            width = page.get_width()
            _text(document, page, font, left, SIDE_PT, right_aligned=False)
            _text(document, page, font, right, width - SIDE_PT, right_aligned=True)
            if not raw.FPDFPage_GenerateContent(page.raw):
                raise RuntimeError(f"PDFium could not write the footer of page {index + 1}")
        finally:
            page.close()


def _text(document: Any, page: Any, font: Any, text: str, x: float,
          right_aligned: bool) -> None:
    import pypdfium2.raw as raw

    obj = raw.FPDFPageObj_CreateTextObj(document.raw, font, ctypes.c_float(FONT_PT))
    encoded = ctypes.create_string_buffer((text + "\x00").encode("utf-16-le"))
    raw.FPDFText_SetText(obj, ctypes.cast(encoded, ctypes.POINTER(raw.FPDF_WCHAR)))
    raw.FPDFPageObj_SetFillColor(obj, *GREY, 255)
    if right_aligned:  # the text's own width, read from its bounds
        left, right = ctypes.c_float(), ctypes.c_float()
        bottom, top = ctypes.c_float(), ctypes.c_float()
        raw.FPDFPageObj_GetBounds(obj, left, bottom, right, top)
        x -= right.value - left.value
    raw.FPDFPageObj_Transform(obj, 1, 0, 0, 1, x, BASELINE_PT)
    raw.FPDFPage_InsertObject(page.raw, obj)
