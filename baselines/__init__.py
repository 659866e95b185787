"""Baseline tuning policies. Every policy has SB3's ``predict`` signature, so a
trained agent and a baseline go through the same evaluation."""

from baselines.adaptive import InnovationAdaptivePolicy
from baselines.paper import PaperPolicy, RealFixedPolicy
from baselines.tuned import TunedFixedPolicy

__all__ = ["InnovationAdaptivePolicy", "PaperPolicy", "RealFixedPolicy", "TunedFixedPolicy"]
