"""The Language-Table-compatible tabletop: pymunk physics, benchmark-camera renderer, gymnasium env, push oracle."""
