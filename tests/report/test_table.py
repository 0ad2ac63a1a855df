"""The heading table's figure."""


def test_figure_panels_by_group_from_zero_with_distinct_colours():
    from matplotlib.colors import to_rgba

    from nfs.scoring.heading_table import HeadingTable, TableRow
    from nfs.report.table_files import plot_heading_table
    rows = [TableRow("before", (0.02, 0.0205)), TableRow("stable", (0.008, 0.0081))]
    rows += [TableRow(f"m{i}", (0.0203 + 1e-4 * i, 0.0204), group="A" if i < 7 else "B")
             for i in range(12)]
    rows += [TableRow("floor", (0.005, 0.005))]
    fig = plot_heading_table(HeadingTable((-30.0, 20.0), tuple(rows)))
    axes = fig.axes
    assert [a.get_title(loc="left") for a in axes] == ["A", "B"]
    for ax in axes:
        assert ax.get_ylim()[0] == 0.0       # a 0.0203-0.0210 spread is not blown up
        labels = [t.get_text() for t in ax.get_legend().get_texts()]
        assert labels[0].startswith("white-noise floor (0.0050 deg)")
        assert "before (uncompensated start-up)" in labels
        # the compensated rows of one panel in different colours
        fills = [to_rgba(c.patches[0].get_facecolor()) for c in ax.containers
                 if c.get_label().startswith("m")]
        assert len(fills) == (7 if ax is axes[0] else 5) and len(set(fills)) == len(fills)
    assert sum(lab.startswith("m") for lab in
               [t.get_text() for t in axes[0].get_legend().get_texts()]) == 7


def test_figure_legends_stand_beside_the_bars_and_name_the_stages():
    # Oracle (invariant): no legend over a panel's bars; the stage rows of a chamber program
    # and the error bars named in words.
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from nfs.scoring.heading_table import HeadingTable, TableRow
    from nfs.report.table_files import plot_heading_table
    rows = (TableRow("before", (0.02,), cell_ci_deg=((0.015, 0.03),)),
            TableRow("held", (0.009,), cell_ci_deg=((0.007, 0.011),)),
            TableRow("ramping", (0.008,), cell_ci_deg=((0.006, 0.01),)),
            TableRow("floor", (0.0046,)))
    fig = plot_heading_table(HeadingTable((10.0,), rows))
    FigureCanvasAgg(fig).draw()
    renderer = fig.canvas.get_renderer()
    (ax,) = fig.axes
    assert ax.get_legend().get_window_extent(renderer).x0 >= \
        ax.get_window_extent(renderer).x1
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert {"chamber held, after the start-up (uncompensated)",
            "chamber ramping (uncompensated)"} <= set(labels)
    assert any(lab.startswith("95 % interval of each cell") for lab in labels)
    assert ax.get_ylim()[0] == 0.0 and ax.get_ylim()[1] >= 0.03     # the top error bar shows
