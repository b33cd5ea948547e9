"""Learning from demonstrations: segmentation, identification of the push model, the OE skill (mappings
(6)/(7)) and the SS skill (DMPs of switches), and the skill sets a task loads or learns. Below planning, which
plans with the learned skills."""
