"""Signal-model thresholds (SSD, ESD) — filled in once the signal models exist."""
