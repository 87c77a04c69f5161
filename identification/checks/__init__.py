"""Checks of an identification, pure numerics on arrays and results (no I/O):

- `fit`: is the data rich enough for the model (signals, excitation, frequency lines) and are
  the estimates physical (flags), around the least squares of eq. (21);
- `band`: is the rate high enough for the first mode and does the band hold it (eq. 29);
- `plausibility`: is the identified model believable on its own log (warnings naming the
  likely cause: a mislabelled log, too little excitation, too little explained).
"""
