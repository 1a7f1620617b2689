"""Streaming input of the live chain: the wire's types (types.py) and, in helper STREAM's branch, the sources."""
