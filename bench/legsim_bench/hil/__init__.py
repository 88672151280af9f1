"""Running scenes: over CAN against hil_sim (can_link, runner, vcan), in legsim_cli for the
analyses that have no frames (cli_run), or with the reference model playing hil_sim
(reference_link). Only recordings come out; the verdicts are legsim_bench.verdict's."""
