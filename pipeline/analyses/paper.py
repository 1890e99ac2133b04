"""Numbers the papers publish that this project computes (the report compares against them)."""

# Filipovic & Kevac (2018), Table 2: feasible share x(i_a) (%) per Table 1 actuator, zero orientation
TABLE2_FEASIBLE_PCT = {1: 100.0, 2: 96.3, 3: 85.19, 4: 87.04, 5: 7.41}
# Section 5.1: actuators accepted at x = 90 %
TABLE2_ACCEPTED = [1, 2]
