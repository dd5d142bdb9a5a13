"""``brdfnorm.audit``: how wrong is a table someone ships, in which convention — and its exact replacement."""
