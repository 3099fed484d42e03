"""The biped (humanoid) side: walking pattern of the Linear Inverted Pendulum."""
