"""Verdicts on recordings: the checks of a leg's run over CAN (checks), of the runs in legsim_cli
(analyses), of the robot's run over CAN (robot_can), against the independent references and
the leg's own equations (leg); each makes an Evaluation of CheckResults (result)."""
