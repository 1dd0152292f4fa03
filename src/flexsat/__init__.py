"""flexsat: integrated structures-and-control design of flexible spacecraft."""

__version__ = "0.1.0"
