"""Time integrators: compiled explicit Runge-Kutta loops and scipy's implicit stiff methods."""
