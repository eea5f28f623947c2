$v = [1, 2, 3] * 2 - [0.5, 0.5, 0.5] / 2;
cube($v + -$v * 0.5);
sphere(r = sqrt(pow(3, 2) + 16) / 2 + sin(30) * cos(60) - floor(PI) % 2 ^ 2, $fn = max([3, 8]));
cylinder(h = norm([3, 4]), d1 = min(4, 2), d2 = len("abc"), $fa = 0.001, $fs = 0);
