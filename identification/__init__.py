"""Identification of joint stiffness after Pham, Gautier, Poignet (ICRA 2001); pure numpy/scipy."""
