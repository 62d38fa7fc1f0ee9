"""Model backends of the generator: one small interface, four implementations.

``anthropic`` (Claude through the SDK), ``offline`` (a deterministic, seeded generator that is not a language
model), ``record`` (wraps another backend and saves every exchange as JSONL) and ``replay`` (serves a saved
transcript back, byte for byte). See :mod:`generator.backends.base` for the interface.
"""
