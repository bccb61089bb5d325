"""The launch interpreter: launch files (XML or YAML) in, one immutable ``LaunchPlan`` out."""
