"""Controllers in the loop: ROSCO through its DISCON interface, a built-in one, and the closed
loop that drives the turbine's actuators from them."""
