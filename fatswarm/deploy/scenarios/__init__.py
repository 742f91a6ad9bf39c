"""Start scenarios: random starts of five kinds, `--init` files and the adversarial families."""
