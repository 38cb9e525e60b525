"""Sub-commands of the seatrack CLI (one module each, exposing ``register(app)``)."""
