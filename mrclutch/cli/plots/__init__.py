"""matplotlib figures, one module per subject (haptic, magnetics, design). Each module
imports matplotlib inside its functions with the non-interactive Agg backend, so the
library never opens a window and never pays for matplotlib unless it draws."""
