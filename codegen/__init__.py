"""mpcgen: FCS-MPC code generator for PMSM drives with bit-for-bit host verification."""

__version__ = "0.1.0"
