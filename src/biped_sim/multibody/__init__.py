"""Multibody assembly: mass matrix, joint constraints, Baumgarte-stabilised forward dynamics."""
