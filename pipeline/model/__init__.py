"""The physics, as data and pure functions: robots (anchors, attachments, platform, per-cable
limits) and their builders, the actuator catalogue and model, kinematics, CPR-WWA dynamics
(Filipovic & Kevac eqs. 10-34), IRPM statics (Hamed & Zohoor eqs. 7-10) and the cable tensions
(minimum-norm and feasible). No config, no files."""
