"""Controllers that use a calibrated model: the reference MPC (:mod:`rcengine.control.mpc`)."""
