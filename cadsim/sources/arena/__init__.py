"""The robot arena (MRC scenario) as a traffic source. Imports no other source."""
