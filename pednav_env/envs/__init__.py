"""Gymnasium environments; registered on ``import pednav_env``."""
