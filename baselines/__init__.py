"""Baseline tuning policies. Every policy has SB3's ``predict`` signature, so a
trained agent and a baseline go through the same evaluation."""

from baselines.paper import PaperPolicy

__all__ = ["PaperPolicy"]
