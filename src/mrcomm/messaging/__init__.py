"""Messaging layer: message types, wire encoding, the AON acknowledged protocol."""
