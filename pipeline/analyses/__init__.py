"""What the declared studies compute from their jobs and how they show it: the actuator choice
(CPR-ACM), the published evidence, the optimiser and the exact drive-train search, the pulling
survival, the figures, the interactive views and the report's web page."""
