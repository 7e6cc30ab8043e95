# Hand-set perceptron weights for Braitenberg obstacle avoidance (mlp, 7 inputs, 2 outputs, tanh).
# Inputs are the 7 IR readings scaled to 0..1 (far left, left, centre, right, far right, back
# left, back right). Genome order: per output neuron, its 7 input weights then its bias.
# A wall on the left speeds up the left wheel and slows the right one (turn right), and the other
# way round; a wall in front turns right; the biases drive forward.
# in:   far-left  left  centre  right  far-right  back-l  back-r  bias
         1.5      2.0   2.5    -2.0   -1.5       0.5     0.5     0.6   # left wheel
        -1.5     -2.0  -2.5     2.0    1.5       0.5     0.5     0.6   # right wheel
