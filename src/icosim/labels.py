"""How figures are named in titles, captions and dataset titles.

>>> figure_label("9"), figure_label("df-baumgarte")
('Fig. 9', 'Figure df-baumgarte')
"""

from __future__ import annotations

__all__ = ["figure_label"]


def figure_label(figure) -> str:
    """``Fig. 9`` for the paper's figures (by number), ``Figure <id>`` for the project's own."""
    return f"Fig. {figure}" if str(figure).isdigit() else f"Figure {figure}"
