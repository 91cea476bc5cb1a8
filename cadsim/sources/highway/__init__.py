"""highway-env's intersection as a traffic source. Imports no other source."""
