"""Pure, vectorised laws, one function per published closed form or constitutive law."""
