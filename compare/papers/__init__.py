"""The paper studies: static filling, discharge, simple shear, and the paper's claims."""
