//! Watertight ray–triangle intersection (Woop, Benthin, Wald, JCGT 2013).
