"""Analyses of an assembled drivetrain: modal (undamped and damped), twist test, state space, forced
response, time simulation, Campbell diagram, sensitivities, calibration, sweeps, identification."""
