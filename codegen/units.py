"""Units of the input-guard limits, by constant name (for generated comments and reports)."""

GUARD_UNITS: dict[str, str] = {
    "I_TRIP_A": "A",
    "UDC_MIN_V": "V",
    "UDC_MAX_V": "V",
    "UC_MIN_V": "V",
    "UC_MAX_V": "V",
    "ANGLE_GUARD_RAD": "rad",
    "OMEGA_GUARD_RAD_S": "rad/s",
    "TORQUE_REF_GUARD_NM": "N*m",
}
