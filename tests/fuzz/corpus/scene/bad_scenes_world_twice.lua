-- expect: line 3: world{} is given twice
world { seconds = 1 }
world { seconds = 2 }
