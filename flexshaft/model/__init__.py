"""The drivetrain: its components and its one assembled model."""
