"""Command lines and studies: ``srenv simulate | bench | sweep | diagnose | fit | config-doc`` (``cli``), the
parameter sweep (cases, local and Ray runners), the performance bench and the v1 action sweep."""
