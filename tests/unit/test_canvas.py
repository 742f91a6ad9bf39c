"""The sub-cell canvas lights the dots under what it draws, to scale, in braille or half blocks."""

from __future__ import annotations

import numpy as np
import pytest

from fatswarm.deploy.view.canvas import BRAILLE_BLANK, Canvas, Viewport


def unit_canvas(cols: int = 4, rows: int = 2, mode: str = "braille") -> Canvas:
    """A canvas where one dot is one world unit and the top-left corner is (0, 8)."""
    dx, dy = (2, 4) if mode == "braille" else (1, 2)
    vp = Viewport.fit(0.0, cols * dx, 8.0 - rows * dy, 8.0, cols, rows, mode)  # type: ignore[arg-type]
    assert vp.units_per_dot == pytest.approx(1.0)
    return Canvas(vp)


def test_point_lights_the_braille_dot_under_it() -> None:
    c = unit_canvas()
    c.point(0.5, 7.5, 1)  # dot column 0, row 0 of cell (0, 0): bit 0x01
    c.point(1.5, 4.5, 1)  # dot column 1, row 3 of cell (0, 0): bit 0x80
    c.point(6.5, 0.5, 1)  # dot column 0, row 3 of cell (3, 1): bit 0x40
    rows = c.glyphs()
    assert rows[0][0] == chr(BRAILLE_BLANK + 0x01 + 0x80)
    assert rows[1][3] == chr(BRAILLE_BLANK + 0x40)
    assert rows[0][1:] == "   " and rows[1][:3] == "   "


def test_half_block_mode_uses_upper_and_lower_halves() -> None:
    c = unit_canvas(mode="half")
    c.point(0.5, 7.5, 1)  # top half of cell (0, 0)
    c.point(1.5, 6.5, 1)  # bottom half of cell (1, 0)
    c.point(2.5, 5.5, 1)  # top and bottom of cell (2, 1)
    c.point(2.5, 4.5, 1)
    assert c.glyphs() == ["▀▄  ", "  █ "]


def test_points_outside_the_canvas_are_clipped() -> None:
    c = unit_canvas()
    c.point(-5.0, 100.0, 1)
    c.disc(1000.0, 1000.0, 3.0, 1)
    c.circle(4.0, 4.0, 50.0, 1)
    assert not c.dots.any()


def test_disc_is_drawn_to_scale_and_round() -> None:
    vp = Viewport.fit(-10.0, 10.0, -10.0, 10.0, 40, 20)  # 80 x 80 dots: a quarter unit per dot
    c = Canvas(vp)
    c.disc(0.0, 0.0, 2.0, 1)
    rows, cols = np.nonzero(c.dots)
    # radius 2 units = 8 dots: the disc spans 16 dots both ways
    assert cols.max() - cols.min() + 1 == 16
    assert rows.max() - rows.min() + 1 == 16
    assert vp.to_cell(0.0, 0.0) == (20, 10)
    assert c.glyphs()[10][20] != " "


def test_disc_smaller_than_a_dot_still_lights_one_dot() -> None:
    vp = Viewport.fit(-1000.0, 1000.0, -1000.0, 1000.0, 20, 10)
    c = Canvas(vp)
    c.disc(3.0, 3.0, 1.0, 1)
    assert int(np.count_nonzero(c.dots)) == 1


def test_circle_outline_leaves_the_centre_empty() -> None:
    vp = Viewport.fit(-10.0, 10.0, -10.0, 10.0, 40, 20)
    c = Canvas(vp)
    c.circle(0.0, 0.0, 8.0, 1)
    rows = c.glyphs()
    for x, y in ((8.0, 0.0), (-8.0, 0.0), (0.0, 8.0), (0.0, -8.0)):
        col, row = vp.to_cell(x * 0.999, y * 0.999)
        assert rows[row][col] != " ", (x, y)
    assert rows[10][20] == " "


def test_highest_layer_wins_a_cell_and_gives_its_style() -> None:
    c = unit_canvas()
    c.point(0.5, 7.5, 2)
    c.point(1.5, 7.5, 5)
    c.point(4.5, 7.5, 3)
    layers = c.cell_layers()
    assert layers[0, 0] == 5 and layers[0, 2] == 3 and layers[1, 0] == 0
    text = c.render({5: "red", 3: "blue"})
    styles = {text.plain[span.start : span.end].strip(): str(span.style) for span in text.spans}
    assert styles[chr(BRAILLE_BLANK + 0x01 + 0x08)] == "red"


def test_viewport_keeps_one_scale_on_both_axes() -> None:
    vp = Viewport.fit(0.0, 100.0, 0.0, 10.0, 50, 10)  # wide box: x decides the scale
    assert vp.units_per_dot == pytest.approx(1.0)
    assert vp.to_dot(50.0, 5.0) == pytest.approx((50.0, 20.0))


def test_viewport_refuses_an_empty_canvas() -> None:
    with pytest.raises(ValueError, match="at least one cell"):
        Viewport.fit(0.0, 1.0, 0.0, 1.0, 0, 5)


def test_a_label_sits_on_a_disc_that_holds_it_in_reverse_video() -> None:
    from fatswarm.deploy.view.canvas import LABEL_ON

    c = unit_canvas(cols=20, rows=6)  # one dot, one unit; (0, 8) top left
    c.disc(20.0, -4.0, 5.0, 3)
    assert c.label(20.0, -4.0, 5.0, "12", 3)
    col, row = c.viewport.to_cell(20.0, -4.0)
    assert c.labels == {(row, col): ("1", LABEL_ON + 3), (row, col + 1): ("2", LABEL_ON + 3)}
    text = "".join(chunk for chunk, _ in c.runs()[row])
    assert "12" in text
    styled = c.render({3: "green"})
    assert any(
        span.style and "reverse" in str(span.style) for span in styled.spans
    )  # the digits read as a block of the disc's colour


def test_a_label_goes_beside_a_small_disc_where_the_cells_are_blank_else_nowhere() -> None:
    c = unit_canvas(cols=20, rows=6)
    c.disc(4.0, 0.0, 1.0, 3)
    assert c.label(4.0, 0.0, 1.0, "7", 3)
    ((_, col), (char, layer)), *_ = c.labels.items()
    assert (char, layer) == ("7", 3)
    assert col > c.viewport.to_cell(5.0, 0.0)[0]  # right of the disc, not on it
    crowded = unit_canvas(cols=20, rows=6)
    crowded.disc(4.0, 0.0, 1.0, 3)
    crowded.disc(8.0, 0.0, 1.0, 3)  # its neighbour takes the cells a label would need
    assert not crowded.label(4.0, 0.0, 1.0, "7", 3)
    assert crowded.labels == {}


def test_clearing_a_disc_keeps_layers_at_or_above_the_bound() -> None:
    c = unit_canvas(cols=20, rows=6)
    c.circle(20.0, -4.0, 6.0, 1)
    c.disc(26.0, -4.0, 1.0, 5)
    c.clear_discs(np.array([[26.0, -4.0], [100.0, 100.0]]), 2.5, below=3)
    jj, ii = np.nonzero(c.dots)
    near = (ii + 0.5 - 26.0) ** 2 + (jj + 0.5 - 12.0) ** 2 <= 2.5**2
    assert (c.dots[jj[near], ii[near]] == 5).all()  # only the disc is left there
    assert (c.dots == 1).any()  # the circle elsewhere
