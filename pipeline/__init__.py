"""cdpr-studies: feasible workspace and actuator choice for cable-driven parallel robots."""
