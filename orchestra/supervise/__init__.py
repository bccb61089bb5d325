"""Process supervision: run a LaunchPlan's nodes, keep them healthy, stop them cleanly."""
