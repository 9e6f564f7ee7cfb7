//! 2-D FFT helpers on ndarray fields (rows then columns, via rustfft). CONTRACT STUB.
