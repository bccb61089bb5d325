"""Launch plans written out for other process managers (``orchestra export``)."""
