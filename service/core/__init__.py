"""Shared pieces of the service: settings, database, security, logging."""
