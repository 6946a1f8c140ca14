// ball.off stretched along x by `s`: every sample is a new subtree key whose
// computation brings that mesh from outside fabatlas (an `import`).
s = 1;
scale([s, 1, 1]) import("ball.off");
