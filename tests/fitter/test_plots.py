"""The line chart's axes: tick grid lines where the values say."""

import numpy as np

from bodyfit.fitter.output.plots import line_chart

GRID = 225  # the grid lines' grey


def _grid_rows(image: np.ndarray) -> list[int]:
    """Rows crossed by a light grey grid line along most of the plot's inside."""
    grey = (image == GRID).all(axis=2)
    return [int(row) for row in np.flatnonzero(grey.sum(axis=1) > 0.5 * image.shape[1])]


def test_a_log_chart_within_one_1_2_5_step_gets_round_linear_ticks():
    """Costs of 13.6-19.5 hold no 1-2-5 value: the grid falls at 14, 16 and 18 instead."""
    low, high = 13.6, 19.5
    image = line_chart({"cost": np.array([high, 16.0, low])}, "t", "x", "y",
                       size_px=(800, 480), log_y=True)
    top, bottom = 52, 50
    expected = [round(top + (np.log10(high) - np.log10(v))
                      / (np.log10(high) - np.log10(low)) * (480 - top - bottom))
                for v in (18.0, 16.0, 14.0)]
    assert _grid_rows(image) == expected


def test_a_log_chart_over_decades_keeps_its_1_2_5_ticks():
    image = line_chart({"cost": np.array([300.0, 30.0, 3.0])}, "t", "x", "y",
                       size_px=(800, 480), log_y=True)
    top, bottom = 52, 50
    span = np.log10(300.0) - np.log10(3.0)
    expected = [round(top + (np.log10(300.0) - np.log10(v)) / span * (480 - top - bottom))
                for v in (200.0, 100.0, 50.0, 20.0, 10.0, 5.0)]
    assert _grid_rows(image) == expected


def test_a_long_title_is_scaled_to_stay_within_the_chart():
    """A title wider than the chart at the usual size (a fit's work line) is drawn smaller,
    its ink within the chart's first and last 4 columns."""
    title = ("local solver from the learned start, 7 iterations, then the cameras' pitch "
             "searched (89 bodies rendered)")  # the demo's work line
    image = line_chart({"cost": np.array([20.0, 15.0])}, title, "x", "y", size_px=(800, 480))
    band = image[:26].min(axis=2) < 128  # the title's dark ink above the plot
    columns = np.flatnonzero(band.any(axis=0))
    assert columns.min() >= 4 and columns.max() <= 800 - 4
    assert columns.max() - columns.min() > 700  # scaled to fit, not far below
