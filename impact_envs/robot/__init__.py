"""Robot side: the controller's dynamics model (Pinocchio) and the MuJoCo scene adapter."""
