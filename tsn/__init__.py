"""tsn package."""
