"""Developer tooling outside the package: sample maker, golden regression, demo (``make samples|golden|demo``)."""
