"""Two-level inverter MPTC (seed 001): published data, switch-table derivation."""
