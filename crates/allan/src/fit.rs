pub struct Fit;
