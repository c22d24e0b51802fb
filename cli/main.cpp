// shadowtiles: one CLI for build, query, inspect, serve (commands are added in cli/command_*.cpp).
int main() { return 0; }
