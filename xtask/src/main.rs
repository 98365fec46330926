fn main() {
    println!("xtask: in progress");
}
