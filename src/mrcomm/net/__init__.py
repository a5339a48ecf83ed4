"""Network layer: link evaluation, network types, perturbations, signal models, buses."""
