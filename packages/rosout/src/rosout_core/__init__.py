"""rosout's logic without processes: the rosout.log line format, its size rotation and the
aggregation step (republish, then write), so all of it is unit-tested in milliseconds."""
