"""``orchestra plot``: rqt_plot's numeric field plots, live from topics or from a bag, drawn
by matplotlib (imported only when a plot is drawn: it is a heavy import)."""
