"""Reports of a verdict: the pass/fail table and the CSV/JSON files (tables), the leg's plots
(plots), the robot's stick figures and animation (robot_plots)."""
