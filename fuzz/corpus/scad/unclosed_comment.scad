cube(1);
/* unterminated comment
cube(2);
