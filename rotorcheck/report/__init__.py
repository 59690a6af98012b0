"""rotorcheck subpackage."""
